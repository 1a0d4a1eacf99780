"""Messages of trust round 4 (issue 42, item 15): the command line names its own way to the parameter names
(``isolator sweep SCENARIO --list``, not ``Simulator.layout.names``), a design refused whole names what the user
swept (``set['isolators[*].position.x']``, not ``isolators[0]``), and a controller with more or fewer sensors than
the scenario is told by counts, never "has None"."""

from __future__ import annotations

import numpy as np
import pytest
import tomli_w
from analysis.test_budget_loop import sensed_table

from conftest import make
from conftest import run_command as run
from isolator import Simulator, load_scenario
from isolator.errors import ParameterError
from isolator.simulation.discrete_controller import DiscreteController
from isolator.sweep import sweep


def test_sweep_list_prints_the_parameter_names(capsys):
    status, out, err = run(["sweep", "paper-table-3-2", "--list"], capsys)
    assert status == 0, err
    assert out.splitlines() == list(Simulator(load_scenario("paper-table-3-2")).layout.names)


def test_an_unknown_name_points_to_the_command_lines_list(tmp_path, capsys):
    status, _, err = run(["sweep", "paper-table-3-2", "--set", "isolators[*].stifness.z=1e5:1e6:3", "--out",
                          str(tmp_path / "rows.csv")], capsys)
    assert status == 2
    assert len(err) == 1
    assert "did you mean 'isolators[*].stiffness.z'?" in err[0]
    assert "'isolator sweep SCENARIO --list' lists them" in err[0]
    assert "Simulator" not in err[0]


def test_sweep_without_out_or_list_is_one_line(capsys):
    status, _, err = run(["sweep", "--set", "table.mass=4000,4400"], capsys)
    assert status == 2
    assert err == ["isolator: error: --out: required: the file the rows go to (.csv or .parquet), or --list for "
                   "the parameter names"]


def test_a_design_refused_whole_names_what_was_swept():
    result = sweep("paper-table-3-2", set={"isolators[*].position.x": [0.0, 0.1]}, workers=1)
    assert result["status"].tolist() == ["invalid", "invalid"]
    for reason in result["reason"]:
        assert reason.startswith("set['isolators[*].position.x']: isolators: positions all lie on one line")
        assert "isolators[0]" not in reason


def idle(sensors: list[str], actuators: list[str]) -> DiscreteController:
    """A controller that reads ``sensors`` and commands nothing."""
    n, m = len(sensors), len(actuators)
    return DiscreteController(1000.0, sensors, actuators, A=np.zeros((0, 0)), B=np.zeros((0, n)),
                              C=np.zeros((m, 0)), D=np.zeros((m, n)))


@pytest.mark.parametrize("change", ["fewer", "more"])
def test_a_controller_with_another_sensor_count_is_told_by_counts(change):
    scenario = make(sensed_table())
    names = [s.name for s in scenario.sensors]
    sensors = names[:-1] if change == "fewer" else [*names, "extra"]
    n = len(sensors)
    controller = idle(sensors, [a.name for a in scenario.actuators])
    with pytest.raises(ParameterError) as caught:
        controller.check_names(scenario)
    message = str(caught.value)
    assert "None" not in message
    assert message.startswith(f"controller.sensors: the controller has {n} where the scenario's [[sensors]] has "
                              f"{len(names)}")


def test_the_budget_command_says_the_counts_too(tmp_path, capsys):
    data = sensed_table()
    path = tmp_path / "table.toml"
    path.write_text(tomli_w.dumps(data))
    folder = tmp_path / "ctrl"
    folder.mkdir()
    idle([s["name"] for s in data["sensors"][:-1]], [a["name"] for a in data["actuators"]]).to_json(
        folder / "controller.json")
    status, _, err = run(["budget", str(path), "--controller", str(folder)], capsys)
    assert status == 2
    assert err == ["isolator: error: --controller sensors: the controller has 11 where the scenario's [[sensors]] "
                   "has 12 ([[sensors]][11] is 'v-z3'; in file order)"]
