"""The trade-off study's error budget (issue 32, "what it buys"): each design's value is the passive budget of
its own linearised table at the tool, the figure says what it shows, the report and designs.csv carry it, and a
scenario without random sources is studied as before with a note."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from isolator import Simulator, load_scenario
from isolator.analysis.budget import AXES, error_budget
from isolator.analysis.linear import linearise
from studies import tradeoff_budget
from studies.tradeoff import run_tradeoff_study

STIFFNESS, DAMPING = [0.5, 1.0, 2.0], [0.5, 1.0, 3.0]


@pytest.fixture(scope="module")
def budget_study(tmp_path_factory):
    figures = []
    patch = pytest.MonkeyPatch()
    patch.setattr(tradeoff_budget, "save_figure", lambda fig, path, dpi=120: figures.append((fig, path)))
    try:
        study = run_tradeoff_study(tmp_path_factory.mktemp("tradeoff-budget"), load_scenario("paper-table-3-2-budget"),
                                   stiffness=STIFFNESS, damping=DAMPING, progress=False, workers=1)
    finally:
        patch.undo()
    return study, figures


def test_each_designs_budget_is_that_of_its_own_table(budget_study):
    study, _ = budget_study
    assert study.budget_point == "probe"  # the first [[points]] entry
    assert np.isfinite(study.budget_rms).all()
    sim = Simulator(study.scenario)
    for i, j in ((0, 0), (1, 1), (2, 2), (0, 2)):
        lin = linearise(study.scenario, parameters=sim.scaled_parameters(STIFFNESS[i], DAMPING[j]))
        rms = error_budget(lin, points=["probe"]).rms[0]
        assert study.budget_rms[i, j] == pytest.approx(rms.max(), rel=1e-12)
        assert study.budget_axis[i, j] == AXES[int(np.argmax(rms))]
    nominal = study.nominal()
    assert study.budget_rms[nominal] == pytest.approx(error_budget(study.scenario).rms[0].max(), rel=1e-9)



def test_the_worst_axis_of_each_design():
    value, axis = tradeoff_budget.worst_axis(np.array([[1.0, 3.0, 2.0], [5.0, 4.0, np.nan], [0.5, 0.25, 0.75]]))
    assert np.array_equal(value[[0, 2]], [3.0, 0.75])
    assert np.isnan(value[1])
    assert list(axis) == ["y", "", "z"]


def test_the_budget_front_by_its_definition(budget_study):
    study, _ = budget_study
    front = study.budget_pareto()
    assert front
    for p in front:
        better = (study.settling_time <= study.settling_time[p]) & (study.budget_rms <= study.budget_rms[p])
        strictly = (study.settling_time < study.settling_time[p]) | (study.budget_rms < study.budget_rms[p])
        assert not np.any(better & strictly)
    on_front = set(front)
    for i in range(len(STIFFNESS)):
        for j in range(len(DAMPING)):
            if (i, j) not in on_front:  # every other design is beaten by one on the front
                assert any(study.settling_time[p] <= study.settling_time[i, j]
                           and study.budget_rms[p] <= study.budget_rms[i, j] for p in front)


def test_the_figure_names_its_axes_and_marks_the_front_and_the_design(budget_study):
    study, figures = budget_study
    (fig, path), = figures
    assert path.name == "budget.png"
    left, right = fig.axes[:2]  # then their colour bars
    assert "[nm]" in left.get_ylabel()
    assert "probe" in left.get_ylabel()
    assert "worst of x, y, z" in left.get_ylabel()
    assert "settling time" in left.get_xlabel()
    assert "[s]" in left.get_xlabel()
    assert "resonance peak" in right.get_ylabel()
    assert "[m/m]" in right.get_ylabel()
    for ax in (left, right):
        labels = [t.get_text() for t in ax.get_legend().get_texts()]
        assert labels == ["design (size: stiffness)", "Pareto front", "scenario's design"]
        assert ax.get_title()
    assert fig.get_suptitle().startswith("paper-table-3-2-budget")
    front = study.budget_pareto()
    line = next(line for line in left.get_lines() if line.get_label() == "Pareto front")
    assert np.allclose(line.get_ydata(), [study.budget_rms[p] * 1e9 for p in front])
    star = next(line for line in left.get_lines() if line.get_label() == "scenario's design")
    assert np.allclose(star.get_ydata(), [study.budget_rms[study.nominal()] * 1e9])


def test_report_and_designs_csv_carry_the_budget(budget_study):
    study, _ = budget_study
    report = (study.folder / "report.md").read_text()
    assert "## Error budget at the tool" in report
    assert "the largest of the x, y and z values" in report
    assert "`probe`" in report
    nominal = study.nominal()
    assert f"{study.budget_rms[nominal] * 1e9:.4g} nm RMS along {study.budget_axis[nominal]}" in report
    rows = list(csv.DictReader((study.folder / "designs.csv").open()))
    assert len(rows) == len(STIFFNESS) * len(DAMPING)
    for row in rows:
        i, j = STIFFNESS.index(float(row["stiffness_scale"])), DAMPING.index(float(row["damping_scale"]))
        assert float(row["budget_rms_m"]) == pytest.approx(study.budget_rms[i, j], rel=1e-5)
        assert row["budget_axis"] == study.budget_axis[i, j]


def test_without_random_sources_the_study_runs_as_before_and_says_why(tmp_path):
    study = run_tradeoff_study(tmp_path, load_scenario("paper-table-3-2"), stiffness=[0.5, 1.0], damping=[1.0, 2.0],
                               progress=False, workers=1)
    assert study.budget_point is None
    assert not study.has_budget
    assert study.budget_pareto() == []
    assert np.isfinite(study.settling_time).all()
    assert not (tmp_path / "budget.png").exists()
    assert "budget" not in (tmp_path / "designs.csv").read_text().splitlines()[0]
    assert "the budget needs a floor spectrum" in (tmp_path / "report.md").read_text()
