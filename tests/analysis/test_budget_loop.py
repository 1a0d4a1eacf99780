"""The closed-loop error budget (issue 32) against a continuous-time loop: velocity feedback sampled so fast that
the hold and the sampling vanish, and against the passive budget for a controller that does nothing."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import solve_continuous_lyapunov

from conftest import active_dict, make
from isolator import linearise
from isolator.analysis.budget import error_budget
from isolator.analysis.sampling import MAX_SAMPLE_RATE
from isolator.errors import ParameterError, UnstableClosedLoopError
from isolator.simulation.discrete_controller import DiscreteController

GAIN = 2.0e4  # N per m/s: skyhook damping per actuator


def sensed_table(noise_psd: float | None = None) -> dict:
    """The active base table (12 actuators, no lag) with a geophone along each actuator's line, no carriage."""
    data = active_dict()
    data["carriages"] = []
    data["points"] = [{"name": "probe", "position": [0.4, 0.2, 0.3]}]
    data["sensors"] = [{"name": f"v-{a['name']}", "on": "table", "position": a["position"],
                        "direction": a["direction"], "quantity": "velocity",
                        **({"noise_psd": noise_psd} if noise_psd is not None else {})}
                       for a in data["actuators"]]
    data["disturbances"] = [{"name": "push", "position": [0.7, -0.3, 0.1], "direction": [0.0, 0.6, 0.8],
                             "psd": 2.0e-2}]
    return data


def skyhook(scenario, gain: float, rate: float, delay: bool = False) -> DiscreteController:
    n = len(scenario.sensors)
    return DiscreteController(rate, [s.name for s in scenario.sensors], [a.name for a in scenario.actuators],
                              method="skyhook", A=np.zeros((0, 0)), B=np.zeros((0, n)), C=np.zeros((n, 0)),
                              D=-gain * np.eye(n), delay=delay)


def test_fast_sampled_velocity_feedback_is_the_continuous_loop():
    """At the fastest rate a controller may have (100 kHz) the sampled skyhook is continuous damping
    ``F = -g v``: the budget's RMS under a white force equals the Lyapunov variance of ``A + B_a D C_s`` (the
    loop closed on the state-space matrices)."""
    scenario = make(sensed_table())
    lin = linearise(scenario)
    budget = error_budget(lin, skyhook(scenario, GAIN, MAX_SAMPLE_RATE), band=(1e-3, 2.0e3))
    sys = lin.system
    inputs, outputs = list(sys.input_labels), list(sys.output_labels)
    a, b, c = np.asarray(sys.A), np.asarray(sys.B), np.asarray(sys.C)
    acts = [inputs.index(f"actuator:{x.name}") for x in scenario.actuators]
    sens = [outputs.index(f"s:{s.name}") for s in scenario.sensors]
    a_cl = a + b[:, acts] @ (-GAIN * np.eye(len(acts))) @ c[sens]
    assert np.all(np.linalg.eigvals(a_cl).real < 0)
    direction, arm = np.array([0.0, 0.6, 0.8]), np.array([0.7, -0.3, 0.1])  # the table is level at rest
    force = [inputs.index(n) for n in ("force:x", "force:y", "force:z", "torque:x", "torque:y", "torque:z")]
    bw = b[:, force] @ np.concatenate([direction, np.cross(arm, direction)])
    p = solve_continuous_lyapunov(a_cl, -np.outer(bw, bw) * 2.0e-2 / 2)
    for axis in "xyz":
        row = c[outputs.index(f"probe:{axis}")]
        exact = math.sqrt(row @ p @ row)
        assert budget.value("probe", axis) == pytest.approx(exact, rel=5e-3), axis
    passive = error_budget(lin)
    assert budget.value("probe", "z") < 0.5 * passive.value("probe", "z")  # the damping works


def test_a_controller_that_does_nothing_gives_the_passive_budget_plus_nothing_from_its_sensors():
    scenario = make(sensed_table(noise_psd=1e-14))
    lin = linearise(scenario)
    idle = error_budget(lin, skyhook(scenario, 0.0, 1000.0), band=(0.1, 400.0))
    passive = error_budget(lin, band=(0.1, 400.0))
    assert idle.sources[:-12] == passive.sources
    np.testing.assert_allclose(idle.rms, passive.rms, rtol=1e-3)
    assert all(idle.value("probe", "z", s) == 0.0 for s in idle.sources if s.startswith("sensor:"))


def test_sensor_noise_through_the_loop_grows_with_the_gain_and_the_delay_costs():
    scenario = make(sensed_table(noise_psd=1e-14))
    lin = linearise(scenario)
    low = error_budget(lin, skyhook(scenario, GAIN / 4, 1000.0))
    high = error_budget(lin, skyhook(scenario, GAIN, 1000.0))
    noise = [s for s in high.sources if s.startswith("sensor:")]
    assert len(noise) == 12
    low_noise = math.sqrt(sum(low.value("probe", "z", s) ** 2 for s in noise))
    high_noise = math.sqrt(sum(high.value("probe", "z", s) ** 2 for s in noise))
    assert high_noise > low_noise > 0
    assert high.controller == "skyhook"
    assert high.band[1] == pytest.approx(0.999 * 500.0)


def test_closed_loop_refusals():
    scenario = make(sensed_table())
    lin = linearise(scenario)
    with pytest.raises(ParameterError, match=r"band: ends at 500 Hz, at or beyond half the controller's sample rate"):
        error_budget(lin, skyhook(scenario, GAIN, 1000.0), band=(0.1, 500.0))
    with pytest.raises(UnstableClosedLoopError, match="controller: the sampled loop is unstable"):
        error_budget(lin, skyhook(scenario, -GAIN * 50, 1000.0))
    other = DiscreteController(1000.0, ["a"], [scenario.actuators[0].name], A=np.zeros((0, 0)), B=np.zeros((0, 1)),
                               C=np.zeros((1, 0)), D=np.zeros((1, 1)))
    with pytest.raises(ParameterError, match=r"controller.sensors\[0\]"):
        error_budget(lin, other)
