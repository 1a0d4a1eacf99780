"""Numerical trouble is reported; actuators are parsed and validated."""

from __future__ import annotations

import pytest

from conftest import base_dict, make
from isolator import ScenarioError, SimulationError, simulate


def test_a_run_that_tips_the_table_over_is_reported():
    data = base_dict()
    data["table"]["mass"] = 20.0
    for iso in data["isolators"]:
        iso["stiffness"] = [2e3, 2e3, 2e3]
        iso["damping"] = [10.0, 10.0, 10.0]
    data["carriages"][0]["mass"] = 2000.0
    data["carriages"][0]["origin"] = [0.0, 0.0, 0.05]
    data["carriages"][0]["profile"] = {"type": "trapezoid", "start": -0.9, "stroke": 1.8, "velocity": 3.0,
                                       "acceleration": 30.0}
    data["gravity"] = 0.0
    with pytest.raises(SimulationError, match=r"^the run diverged: the table turned by more than 0\.2 rad"):
        simulate(make(data))


def test_actuators_are_parsed_and_checked():
    data = base_dict()
    data["actuators"] = [{"name": "z-fl", "position": [1.0, 0.5, -0.15], "direction": [0.0, 0.0, 1.0],
                          "max_force": 500.0, "bandwidth": 100.0}]
    sc = make(data)
    assert sc.actuators[0].max_force == 500.0
    assert sc.actuators[0].bandwidth == 100.0
    data["actuators"][0]["direction"] = [0.0, 0.0, 2.0]
    with pytest.raises(ScenarioError, match=r"^actuators\[0\]\.direction: must be a unit vector"):
        make(data)
    data["actuators"][0]["direction"] = [0.0, 0.0, 1.0]
    data["actuators"][0]["max_force"] = 0.0
    with pytest.raises(ScenarioError, match=r"^actuators\[0\]\.max_force: must be > 0"):
        make(data)
    data["actuators"][0]["max_force"] = 500.0
    data["actuators"].append(dict(data["actuators"][0]))
    with pytest.raises(ScenarioError, match=r"^actuators\[1\]\.name: 'z-fl' is used twice"):
        make(data)
