"""The robustness study: tolerances parsed and expanded element by element, Latin-hypercube samples within
them, the sweep's settling times equal to single runs of the same machines, the ranking, the command."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from isolator import Band, ParameterError, Simulator, load_scenario
from isolator.cli.app import main
from isolator.sweep import sweep
from studies.robustness import MethodSpread, RobustnessStudy
from studies.tolerances import Tolerance, draw_samples, parse_tolerance, sweep_columns, varied_parameters

SCENARIO = "paper-table-3-2"


@pytest.fixture(scope="module")
def sim():
    return Simulator(load_scenario(SCENARIO))


@pytest.mark.parametrize(("text", "expected"), [
    ("table.mass=+-5%", Tolerance("table.mass", 0.05, True)),
    ("isolators[*].position=+-0.002", Tolerance("isolators[*].position", 0.002, False)),
    ("isolators[0].stiffness = ±10 %", Tolerance("isolators[0].stiffness", 0.10, True)),
    ("carriages[*].mass=+/-2.5%", Tolerance("carriages[*].mass", 0.025, True)),
])
def test_tolerances_parse(text, expected):
    got = parse_tolerance(text)
    assert got.name == expected.name
    assert got.relative == expected.relative
    assert got.amount == pytest.approx(expected.amount, rel=1e-15)


@pytest.mark.parametrize(("text", "match"), [
    ("table.mass", "expected NAME=\\+-AMOUNT"),
    ("table.mass=5%", "must read \\+-5%"),
    ("table.mass=+-x%", "'x' is not a number"),
    ("table.mass=+-0%", "finite number > 0"),
    ("table.mass=+-nan", "finite number > 0"),
    ("table.mass=+-100%", "below 100 %"),
])
def test_malformed_tolerances_are_named(text, match):
    with pytest.raises(ParameterError, match=match):
        parse_tolerance(text)


def test_every_element_varies_on_its_own(sim):
    tols = [parse_tolerance(t) for t in ("isolators[*].stiffness=+-10%", "isolators[*].position=+-0.002",
                                         "table.mass=+-5%")]
    varied = varied_parameters(tols, sim.layout, sim.parameters)
    names = [v.name for v in varied]
    # relative: one factor per isolator (its three axes together); absolute: every component on its own
    assert names[:4] == [f"isolators[{i}].stiffness" for i in range(4)]
    assert names[4:16] == [f"isolators[{i}].position.{a}" for i in range(4) for a in "xyz"]
    assert names[16] == "table.mass"
    assert varied[4].nominal == pytest.approx(1.0)  # isolators[0].position.x of the bundled file


@pytest.mark.parametrize(("text", "match"), [
    ("isolators[*].stifness=+-10%", "did you mean 'isolators\\[\\*\\].stiffness'"),
    ("carriages[0].origin.x=+-5%", "cannot vary by a fraction of its value, which is 0"),
    ("table.mass=+-5000", "table.mass cannot vary that much"),
    ("table[*].mass=+-5%", "has no elements"),
])
def test_tolerances_that_cannot_apply_are_refused(sim, text, match):
    with pytest.raises(ParameterError, match=match):
        varied_parameters([parse_tolerance(text)], sim.layout, sim.parameters)


def test_latin_hypercube_samples_fill_each_stratum_once(sim):
    varied = varied_parameters([parse_tolerance("isolators[*].damping=+-20%"),
                                parse_tolerance("isolators[0].position.z=+-0.001")], sim.layout, sim.parameters)
    n = 40
    values = draw_samples(varied, n, seed=3)
    assert values.shape == (n, 5)
    factors, z = values[:, :4], values[:, 4]
    assert np.all((factors >= 0.8) & (factors <= 1.2))
    assert np.all(np.abs(z - varied[4].nominal) <= 0.001)
    strata = np.floor((factors - 0.8) / 0.4 * n).astype(int)  # Latin hypercube: one sample per stratum
    for column in strata.T:
        assert sorted(column) == list(range(n))
    assert np.array_equal(values, draw_samples(varied, n, seed=3))
    assert not np.array_equal(values, draw_samples(varied, n, seed=4))


def test_swept_machines_equal_single_runs(sim):
    """The study's sweep columns drive exactly the parameters a hand-built vector changes."""
    tols = [parse_tolerance(t) for t in ("isolators[*].stiffness=+-10%", "isolators[1].position=+-0.002",
                                         "carriages[0].mass=+-5%")]
    varied = varied_parameters(tols, sim.layout, sim.parameters)
    values = draw_samples(varied, 3, seed=1)
    absolute, relative = sweep_columns(varied, values)
    band = Band.absolute({"x": 2e-5, "y": 4e-6, "z": 3e-7, "rx": 2e-5, "ry": 1e-4, "rz": 3e-7})
    result = sweep(SCENARIO, set=absolute, scale=relative, zip=True, band=band, workers=1)
    index = {n: i for i, n in enumerate(sim.layout.names)}
    for k in range(3):
        p = sim.parameters.copy()
        for j, v in enumerate(varied):
            for name in sim.layout.names:
                if name == v.name or name.startswith(v.name + "."):
                    p[index[name]] = p[index[name]] * values[k, j] if v.relative else values[k, j]
        single = sim.run(p=p, band=band).settling_time_max
        assert result["settling_time_max"][k] == pytest.approx(single, abs=1e-9)


def _study(samples: np.ndarray, times: dict[str, np.ndarray]) -> RobustnessStudy:
    sim = Simulator(load_scenario(SCENARIO))
    varied = varied_parameters([parse_tolerance("isolators[0].damping=+-20%"),
                                parse_tolerance("table.mass=+-5%")], sim.layout, sim.parameters)
    methods = {k: MethodSpread(k, None, v) for k, v in times.items()}
    return RobustnessStudy(sim.scenario, varied, samples, methods, Band(), Path("not-written"))


def test_percentiles_benefit_and_ranking_by_hand():
    rng = np.random.default_rng(0)
    samples = np.column_stack([rng.uniform(0.8, 1.2, 50), rng.uniform(0.95, 1.05, 50)])
    paper = 3.0 - 2.0 * samples[:, 0]  # settles sooner with more damping, regardless of the mass
    study = _study(samples, {"paper": paper, "ZVD": paper - 0.5})
    ranking = study.ranking("paper")
    assert ranking[0] == ("isolators[0].damping", pytest.approx(-1.0))
    assert abs(ranking[1][1]) < 0.4
    assert study.methods["paper"].percentile(50) == pytest.approx(np.percentile(paper, 50, method="higher"))
    assert np.allclose(study.benefit("ZVD"), 0.5)
    data = study.to_dict()["methods"]["ZVD"]["benefit"]
    assert data["p50"] == pytest.approx(0.5)
    assert data["better_share"] == 1.0


def test_machines_without_a_settling_time_count_as_slowest():
    times = np.array([1.0, 2.0, np.nan, 3.0])
    spread = MethodSpread("paper", 1.0, times)
    assert spread.failed == 1
    assert math.isnan(spread.worst)
    assert spread.percentile(50) == 3.0  # the higher of the two middle machines: conservative
    assert spread.percentile(25) == 2.0
    assert math.isnan(spread.percentile(95))  # the missing machine is the slowest quarter


@pytest.mark.slow
def test_robustness_command(tmp_path, capsys):
    out = tmp_path / "robust"
    assert main(["study", "robustness", SCENARIO, "--quick", "--samples", "8", "--out", str(out),
                 "--tolerance", "isolators[*].stiffness=+-10%", "--tolerance", "table.mass=+-5%"]) == 0
    printed = capsys.readouterr().out
    assert "matters most:" in printed
    data = json.loads((out / "results.json").read_text())
    assert set(data["methods"]) == {"paper", "ZVD", "optimised"}
    assert data["samples"] == 8
    for name in ("cdf.png", "sensitivity.png", "samples.csv", "report.md"):
        assert (out / name).stat().st_size > 0
    # the optimised and ZVD profiles settle sooner than the paper's on the nominal machine, in one band
    methods = data["methods"]
    assert methods["ZVD"]["nominal"] < methods["paper"]["nominal"]
    assert methods["optimised"]["nominal"] < methods["paper"]["nominal"]


def test_robustness_command_bad_tolerance(tmp_path, capsys):
    code = main(["study", "robustness", SCENARIO, "--out", str(tmp_path / "r"),
                 "--tolerance", "isolators[*].stifness=+-10%"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1
    assert "did you mean 'isolators[*].stiffness'" in err[0]


@pytest.mark.parametrize(("options", "match"), [
    (["--samples", "0"], "--samples: must be a whole number >= 1"),
    (["--workers", "0"], "--workers: must be a whole number >= 1"),
    (["--tolerance", "carriages[0].origin.x=+-5%"], "cannot vary by a fraction of its value, which is 0"),
])
def test_robustness_command_bad_options(tmp_path, capsys, options, match):
    assert main(["study", "robustness", SCENARIO, "--out", str(tmp_path / "r"), *options]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert match in err[0]


def test_the_benefit_is_in_cycle_time_and_failures_rank_slowest():
    rng = np.random.default_rng(1)
    samples = np.column_stack([rng.uniform(0.8, 1.2, 40), rng.uniform(0.95, 1.05, 40)])
    paper = np.full(40, 2.0)
    paper[samples[:, 0] < 0.85] = np.nan  # the least damped machines do not settle with the paper profile
    shaped = np.full(40, 0.5)
    study = _study(samples, {"paper": paper, "ZVD": shaped})
    study.methods["paper"] = MethodSpread("paper", 2.0, paper, move_time=7.4)
    study.methods["ZVD"] = MethodSpread("ZVD", 0.5, shaped, move_time=7.7)
    benefit = study.benefit("ZVD")
    settled = ~np.isnan(paper)
    assert np.allclose(benefit[settled], (7.4 + 2.0) - (7.7 + 0.5))  # 1.2 s, not the 1.5 s of settling alone
    assert np.all(np.isposinf(benefit[~settled]))  # a machine the paper profile never settles on
    assert study.methods["paper"].percentile(50, "cycle") == pytest.approx(9.4)
    # the damping decides which machines fail: it ranks first though those machines have no settling time
    assert study.ranking("paper")[0][0] == "isolators[0].damping"
    assert study.ranking("paper")[0][1] < -0.5


def test_the_robustness_study_refuses_a_sequence(tmp_path, capsys):
    assert main(["study", "robustness", "paper-table-3-2-sequence", "--out", str(tmp_path / "r")]) == 2
    assert "robustness study varies a single move" in capsys.readouterr().err


def test_figures_and_report_when_a_method_never_settles(tmp_path):
    """No settled machine for a method: the CDF has a legend entry instead of a curve, the report says so."""
    from studies.robustness_report import plot_cdf, write_robustness_report

    samples = np.column_stack([np.linspace(0.8, 1.2, 6), np.linspace(0.95, 1.05, 6)])
    study = _study(samples, {"paper": np.full(6, np.nan), "ZVD": np.array([0.4, 0.5, np.nan, 0.6, 0.5, 0.4])})
    band = Band.absolute({"x": 2e-5, "y": 4e-6, "z": 3e-7, "rx": 2e-5, "ry": 1e-4, "rz": 3e-7})
    study = RobustnessStudy(study.scenario, study.varied, study.samples, study.methods, band, tmp_path)
    assert plot_cdf(study).stat().st_size > 0
    report = write_robustness_report(study).read_text()
    assert "+∞ (the paper profile does not settle)" in report
    data = study.to_dict()["methods"]["ZVD"]["benefit"]
    assert data["only_paper_unsettled"] == 5
    assert data["compared"] == 5  # machine 2: neither settles
    assert data["p50"] == "+inf"


def test_benefit_percentiles_are_the_lower_order_statistic():
    samples = np.column_stack([np.linspace(0.8, 1.2, 4), np.linspace(0.95, 1.05, 4)])
    study = _study(samples, {"paper": np.array([2.0, 2.0, 2.0, 2.0]), "ZVD": np.array([1.0, 1.5, 0.5, np.nan])})
    data = study.to_dict()["methods"]["ZVD"]["benefit"]
    assert data["p5"] == "-inf"  # the machine ZVD does not settle on
    assert data["p50"] == pytest.approx(0.5)  # of -inf, 0.5, 1.0, 1.5: the lower middle one
    assert data["only_method_unsettled"] == 1


def test_the_cdf_figure_shows_its_axis_labels_whole(tmp_path, monkeypatch):
    """Issue 26, item 7: the benefit panel's x-label was cut off at the figure's right edge."""
    import dataclasses

    import studies.robustness_report as report

    rng = np.random.default_rng(0)
    samples = np.column_stack([rng.uniform(0.8, 1.2, 50), rng.uniform(0.95, 1.05, 50)])
    paper = 3.0 - 2.0 * samples[:, 0]
    study = dataclasses.replace(_study(samples, {"paper": paper, "ZVD": paper - 0.5}), folder=tmp_path)
    inside = []

    def check(fig, path, *args, **kwargs):
        fig.canvas.draw()
        renderer, box = fig.canvas.get_renderer(), fig.bbox
        for ax in fig.axes:
            for label in (ax.xaxis.label, ax.yaxis.label):
                extent = label.get_window_extent(renderer)
                inside.append(box.x0 <= extent.x0 and extent.x1 <= box.x1 and box.y0 <= extent.y0)

    monkeypatch.setattr(report, "save_figure", check)
    report.plot_cdf(study)
    assert inside
    assert all(inside)
