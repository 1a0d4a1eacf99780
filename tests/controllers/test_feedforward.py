"""Actuator forces in the simulation, and feedforward cancellation checked independently."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from conftest import active_dict, base_dict, make
from controllers.feedforward import compare_feedforward, feedforward_allocation
from isolator import ParameterError, ScenarioError, Simulator, load_scenario
from isolator.cli.app import main
from isolator.scenario.definitions import SIGNALS
from isolator.simulation.actuation import ForceHistory, applied_forces, load_forces
from isolator.validation.multibody import MujocoTable, mujoco_available


@pytest.mark.skipif(not mujoco_available(), reason="needs mujoco")
def test_unlimited_allocation_leaves_the_table_on_its_quasi_static_path_in_mujoco():
    scenario = make(active_dict(max_force=1e6))
    ff = feedforward_allocation(scenario, limits=False)
    passive = MujocoTable(scenario).simulate(rtol=1e-9, atol=1e-13)

    def forces(t: float, piece_time: float) -> np.ndarray:
        return ff.forces.command(np.array([t]), np.array([piece_time]))[0]

    controlled = MujocoTable(scenario, forces=forces).simulate(rtol=1e-9, atol=1e-13)
    qs = ff.path(passive.t).T
    for k, name in enumerate(SIGNALS):
        dev_p = np.max(np.abs(passive.signals[k] - qs[k]))
        dev_c = np.max(np.abs(controlled.signals[k] - qs[k]))
        if dev_p > 1e-12:
            assert 20 * math.log10(dev_c / dev_p) < -40, name
    # and our simulation of the same forces agrees with MuJoCo's
    ours = Simulator(scenario).run(forces=ff.forces)
    scale = np.max(np.abs(controlled.signals), axis=1)
    np.testing.assert_allclose(ours.signals, controlled.signals, atol=1e-5 * scale.max())


def test_targets_on_the_active_paper_scenario():
    result = compare_feedforward(load_scenario("paper-table-3-2-active"))
    assert all(v <= -40 for v in result.reduction_db().values())
    assert result.settling_time_max("controlled") <= 0.020
    assert result.settling_time_max("passive") > 1.0
    assert all(f <= 500.0 for f in result.feedforward.max_force.values())
    data = result.to_dict()
    for which in ("passive", "controlled"):
        assert set(data[which]) >= {"peak", "settling_time_max"}
        assert set(data[which]["peak"]) == set(SIGNALS)
    assert len(data["max_force"]) == 12


def test_force_limits_are_respected():
    scenario = make(active_dict(max_force=15.0))
    ff = feedforward_allocation(scenario)
    assert np.max(np.abs(ff.forces.forces)) <= 15.0 + 1e-9
    assert np.max(np.abs(ff.residual)) > 1.0  # the limits leave part of the wrench
    doubled = ForceHistory(ff.forces.t, 2 * ff.forces.forces, ff.forces.names)
    run = Simulator(scenario).run(forces=doubled)
    assert np.max(np.abs(run.actuator_forces)) <= 15.0 + 1e-9  # the simulation clips commands


def test_first_order_lag_is_exact():
    scenario = make(active_dict(bandwidth=20.0))
    tau = 1 / (2 * math.pi * 20.0)
    times = np.linspace(0.0, 0.05, 51)
    command = np.zeros((51, 12))
    command[:, 0] = 100.0  # a step at t = 0 (the lag starts from zero force)
    command[:, 1] = 1000.0 * times  # a ramp
    out = applied_forces(scenario, command, times)
    np.testing.assert_allclose(out[:, 0], 100.0 * (1 - np.exp(-times / tau)), rtol=1e-12, atol=1e-12)
    ramp = np.minimum(1000.0 * (times - tau * (1 - np.exp(-times / tau))), 500.0)
    np.testing.assert_allclose(out[:, 1], ramp, rtol=1e-9, atol=1e-9)


def test_forces_files(tmp_path: Path):
    scenario = make(active_dict())
    path = tmp_path / "f.csv"
    path.write_text("t,z0,x1\n0,0,0\n0.5,0,0\n0.5,100,-20\n1,100,-20\n")
    forces = load_forces(path, scenario)
    cmd = forces.command(np.array([0.5, 0.5, 0.75]), np.array([0.4, 0.6, 0.75]))
    assert cmd[0, forces.names.index("z0")] == 0.0  # before the step
    assert cmd[1, forces.names.index("z0")] == 100.0  # after it
    assert cmd[2, forces.names.index("x1")] == -20.0
    assert np.all(cmd[:, forces.names.index("y2")] == 0.0)  # not named: zero
    bad = tmp_path / "bad.csv"
    bad.write_text("t,nope\n0,1\n")
    with pytest.raises(ParameterError, match=r"^forces: '.*bad\.csv' line 1: column 'nope' is not one of t, "):
        load_forces(bad, scenario)
    bad.write_text("t,z0\n1,0\n0,1\n")
    with pytest.raises(ParameterError, match=r"^forces: '.*bad\.csv' line 3: t = 0 is not after 1 on line 2"):
        load_forces(bad, scenario)
    with pytest.raises(ScenarioError, match="no \\[\\[actuators\\]\\]"):
        load_forces(path, make(base_dict()))


def test_feedforward_and_forces_commands(tmp_path: Path, capsys):
    out = tmp_path / "ff.csv"
    assert main(["feedforward", "--json", "--out", str(out)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data) >= {"passive", "controlled", "max_force"}
    assert data["controlled"]["settling_time_max"] <= 0.02
    assert main(["simulate", "paper-table-3-2-active", "--forces", str(out), "--json"]) == 0
    run = json.loads(capsys.readouterr().out)
    assert run["peak"]["z"] < 0.05 * data["passive"]["peak"]["z"]
    assert main(["feedforward", "paper-table-3-2"]) == 2
    assert "no [[actuators]]" in capsys.readouterr().err


# -- optimal feedforward ---------------------------------------------------------------
def test_optimal_feedforward_beats_allocation_with_slow_actuators():
    data = active_dict(bandwidth=20.0)
    for act in data["actuators"]:
        act["max_rate"] = 2e4
    scenario = make(data)
    from controllers.feedforward import feedforward_optimal

    optimal = feedforward_optimal(scenario)
    assert optimal.method == "optimal"
    with_optimal = compare_feedforward(scenario, optimal)
    with_allocation = compare_feedforward(scenario)
    red_opt, red_alloc = with_optimal.reduction_db(), with_allocation.reduction_db()
    passive = with_optimal.deviation_peak("passive")
    largest = {"r": max(passive[k] for k in ("rx", "ry", "rz")), "t": max(passive[k] for k in "xyz")}
    moving = [k for k in SIGNALS if passive[k] > 1e-3 * largest["r" if k.startswith("r") else "t"]]
    assert set(moving) == {"x", "z", "ry"}  # the x move on the symmetric table
    for k in moving:
        assert red_opt[k] <= -40, (k, red_opt[k])
        assert red_opt[k] <= red_alloc[k] - 20, (k, red_opt[k], red_alloc[k])
    assert max(with_optimal.settling["controlled"][k] for k in moving) <= 0.020
    # limits: force and rate of the command, and what the actuators apply in the run
    f, t = optimal.forces.forces, optimal.forces.t
    assert np.abs(f).max() <= 500.0 * (1 + 1e-6)
    assert np.max(np.abs(np.diff(f, axis=1)) / np.diff(t)) <= 2e4 * (1 + 1e-4)
    assert np.abs(with_optimal.controlled.actuator_forces).max() <= 500.0 + 1e-9
    assert with_optimal.to_dict()["method"] == "optimal"


def test_optimal_feedforward_failures_are_reported():
    from controllers.feedforward import OptimalSettings, feedforward_optimal
    from isolator import OptimisationError

    scenario = make(active_dict())
    with pytest.raises(OptimisationError, match=r"stopped with '.*' after 1 iterations; the best point") as info:
        feedforward_optimal(scenario, OptimalSettings(max_iterations=1))
    assert info.value.feedforward.forces.forces.shape[0] == len(scenario.actuators)
    data = active_dict()
    data["carriages"][0]["profile"] = {"type": "sine", "amplitude": 0.1, "omega": 3.0}
    with pytest.raises(ScenarioError, match="needs moves that stop"):
        feedforward_optimal(make(data))
