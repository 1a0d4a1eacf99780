"""Sweeps' error-budget columns (issue 32, "what it buys"): each design's ``budget:<point>:<axis>`` is the passive
budget of that design's table, the columns only when asked for, bad requests one line and exit 2, nothing
written."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from conftest import base_dict, make
from conftest import run_command as run
from isolator import load_scenario
from isolator.analysis.budget import error_budget
from isolator.analysis.linear import linearise
from isolator.errors import ParameterError, ScenarioError
from isolator.model.parameters import ParameterLayout
from isolator.sweep import build_designs, sweep
from isolator.sweep.budget import budget_requests

SCALE = {"isolators[*].stiffness": [0.5, 2.0], "isolators[*].damping": [0.5, 3.0]}


def test_budget_columns_are_each_designs_passive_budget(tmp_path: Path):
    scenario = load_scenario("paper-table-3-2-budget")
    out = tmp_path / "rows.csv"
    result = sweep(scenario, scale=SCALE, zip=True, workers=1, budget=["probe:z", "lens:x", "probe:y"],
                   frequencies=[10.0], out=out)
    columns = list(csv.DictReader(out.open()).fieldnames or [])
    assert columns[-3:] == ["budget:probe:z", "budget:lens:x", "budget:probe:y"]
    assert columns[-4] == "transmissibility:z@10Hz"
    layout = ParameterLayout.of(scenario)
    designs = build_designs(layout, layout.pack(scenario), None, SCALE, True, None, "sobol", 0)
    values = []
    for i, p in enumerate(designs.parameters(0, designs.count)):
        budget = error_budget(linearise(scenario, parameters=p))  # default band, carriages at their start
        for point, axis in (("probe", "z"), ("lens", "x"), ("probe", "y")):
            assert result[f"budget:{point}:{axis}"][i] == pytest.approx(budget.value(point, axis), rel=1e-12)
        values.append(budget.value("probe", "z"))
    # the column follows each design's parameters, not the scenario's nominal table
    nominal = error_budget(scenario).value("probe", "z")
    assert abs(values[0] - values[1]) > 1e-3 * nominal
    assert json.loads(out.with_name("rows.csv.sweep.json").read_text())["budget"] == [
        "budget:probe:z", "budget:lens:x", "budget:probe:y"]


def test_without_budget_the_sweep_and_its_description_are_as_before(tmp_path: Path):
    out = tmp_path / "rows.csv"
    sweep("paper-table-3-2-budget", scale={"isolators[*].damping": [1.0]}, workers=1, out=out)
    assert not any(c.startswith("budget:") for c in csv.DictReader(out.open()).fieldnames or [])
    assert "budget" not in json.loads(out.with_name("rows.csv.sweep.json").read_text())


def test_requests_are_checked_against_the_scenario():
    scenario = load_scenario("paper-table-3-2-budget")
    assert budget_requests(scenario, "probe:z, lens:x") == (("probe", "z"), ("lens", "x"))
    assert budget_requests(scenario, None) == ()
    for bad, named in (("tool:z", "no point named 'tool' (have: probe, lens)"), ("probe:rz", "must be x, y or z"),
                       ("probe", "expected POINT:AXIS"), ("probe:z,probe:z", "probe:z is asked for twice"),
                       ("table:z", "no point named 'table'")):
        with pytest.raises(ParameterError, match="budget: ") as info:
            budget_requests(scenario, bad)
        assert named in str(info.value)
    # a scenario without [[points]] has its mass centre, "table"
    data = base_dict()
    data["ground"] = {"spectrum": {"vc": "VC-C"}}
    assert budget_requests(make(data), ["table:z"]) == (("table", "z"),)
    with pytest.raises(ScenarioError, match="no random source"):
        budget_requests(load_scenario("paper-table-3-2"), ["table:z"])


@pytest.mark.parametrize(("scenario", "budget", "named"), [
    ("paper-table-3-2-budget", "tool:z", "budget: no point named 'tool'"),
    ("paper-table-3-2-budget", "probe:w", "budget: the axis of 'probe:w' must be x, y or z"),
    ("paper-table-3-2", "table:z", "budget: the scenario has no random source"),
])
def test_bad_budget_on_the_command_line_is_one_line_and_nothing_written(tmp_path: Path, capsys, scenario, budget,
                                                                        named):
    out = tmp_path / "rows.csv"
    status, _, err = run(["sweep", scenario, "--scale", "isolators[*].damping=1,2", "--budget", budget,
                          "--workers", "1", "--out", str(out)], capsys)
    assert status == 2
    assert len(err) == 1, err
    assert named in err[0], err
    assert not out.exists()
    assert not out.with_name("rows.csv.sweep.json").exists()


def test_budget_from_the_command_line(tmp_path: Path, capsys):
    out = tmp_path / "rows.csv"
    status, _, err = run(["sweep", "paper-table-3-2-budget", "--scale", "isolators[*].damping=1,2", "--budget",
                          "probe:z,probe:x", "--budget", "lens:y", "--workers", "1", "--out", str(out)], capsys)
    assert status == 0, err
    rows = list(csv.DictReader(out.open()))
    assert [c for c in rows[0] if c.startswith("budget:")] == ["budget:probe:z", "budget:probe:x", "budget:lens:y"]
    assert all(np.isfinite(float(r["budget:lens:y"])) and float(r["budget:lens:y"]) > 0 for r in rows)


def test_resume_keeps_the_budget_columns_and_refuses_other_ones(tmp_path: Path):
    out = tmp_path / "rows.csv"
    first = sweep("paper-table-3-2-budget", scale={"isolators[*].damping": [1.0, 2.0]}, budget="probe:z", workers=1,
                  out=out)
    again = sweep("paper-table-3-2-budget", scale={"isolators[*].damping": [1.0, 2.0]}, budget="probe:z", workers=1,
                  out=out, resume=True)
    assert np.array_equal(again["budget:probe:z"], first["budget:probe:z"])
    for budget, named in (("probe:x", "differs in: budget"), (None, "holds other columns than this sweep's")):
        with pytest.raises(ParameterError, match=named):
            sweep("paper-table-3-2-budget", scale={"isolators[*].damping": [1.0, 2.0]}, budget=budget, workers=1,
                  out=out, resume=True)
