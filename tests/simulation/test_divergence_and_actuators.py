"""Numerical trouble is reported; actuators are parsed and validated."""

from __future__ import annotations

import numpy as np
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


def test_a_non_finite_dense_output_anywhere_is_reported_with_its_step(monkeypatch):
    """A stage that feeds only the dense output (DOP853's last three), in a row the signals do not read (a
    velocity): no later step's start and no peak shows it, the run's check of its whole dense output does."""
    import isolator.simulation.simulator as simulator_module
    from isolator import Simulator, load_scenario

    real = simulator_module.dense_run
    spoiled = 287

    def dense_run(*args):
        plan, (raw, peaks, deviations, polynomials, signals) = real(*args)
        polynomials = polynomials.copy()
        polynomials[spoiled, -1, 7:13] = np.nan
        return plan, (raw, peaks, deviations, polynomials, signals)

    monkeypatch.setattr(simulator_module, "dense_run", dense_run)
    sim = Simulator(load_scenario("paper-table-3-2"))
    plan = sim.method_of(*sim.equilibria(sim.parameters)).plan
    when = f"{plan.start[spoiled]:.4g}"
    with pytest.raises(SimulationError, match=rf"^the run diverged: non-finite state at t = {when} s"):
        sim.run()
