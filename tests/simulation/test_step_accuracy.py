"""The simulator's own steps are as accurate as a converged run: the actuators' lags among the rates the RK4
steps resolve (forces, controllers), the leveling valves' switches as DOP853 step ends (pneumatic tables); the
lags' windowed sums against their closed forms."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from controllers.feedback import design_controller
from isolator import Simulator, load_scenario
from isolator.numerics.dop853 import DenseStepper
from isolator.scenario.ground import Ground
from isolator.scenario.profiles import SineProfile
from isolator.simulation.actuation import ForceHistory, applied_forces
from isolator.simulation.leveling import sensor_heights
from isolator.simulation.stepping import STEP_ANGLE, Method, fastest_rate
from isolator.simulation.valve_events import ValveSwitches, dense_run


def shortened(name: str, duration: float):
    scenario = load_scenario(name)
    return dataclasses.replace(scenario, simulation=dataclasses.replace(scenario.simulation, duration=duration))


def columns(response) -> dict[str, np.ndarray]:
    """Every output of a run: signals, sensors, pressures and heights."""
    out = {n: response.signals[i] for i, n in enumerate(response.signal_names)}
    out |= {f"s:{n}": response.sensor_signals[i] for i, n in enumerate(response.sensor_names)}
    return out | (response.pneumatic.columns if response.pneumatic is not None else {})


def worst(got, reference) -> float:
    """The largest error of any output, relative to that output's peak."""
    a, b = columns(got), columns(reference)
    return max(float(np.max(np.abs(a[n] - b[n])) / np.max(np.abs(b[n]))) for n in b if np.max(np.abs(b[n])) > 0)


class Refined(Simulator):
    """The simulator with eight times as many RK4 steps as its rule gives, closed loops included."""

    def substeps_for(self, *args, **kwargs) -> int:
        return 8 * super().substeps_for(*args, **kwargs)


def test_the_lags_are_among_the_rates_of_actuated_runs_only():
    scenario = load_scenario("paper-table-3-2-geophones")
    lag = 2 * math.pi * 200.0
    assert fastest_rate(scenario, 40.0) == 40.0
    assert fastest_rate(scenario, 40.0, actuated=True) == pytest.approx(lag)
    shaken = dataclasses.replace(scenario, ground=Ground(motion={"z": SineProfile(1e-6, 2e3)}))
    assert fastest_rate(shaken, 40.0) == 2e3
    sim = Simulator(scenario)
    assert sim.substeps_for(40.0, actuated=True) == math.ceil(lag * 1e-3 / STEP_ANGLE)
    assert sim.method_for(40.0, actuated=True).plan is None


@pytest.mark.parametrize("amplitude", [400.0, 700.0])  # 700: clipped at the actuator's 500 N
def test_a_forced_run_of_lagged_actuators_equals_a_converged_one(amplitude):
    """Twelve actuators with a 200 Hz lag (0.8 ms) driven by sines sampled at 1 ms: before the lag's rate was
    among the step rule's, one RK4 step per millisecond strayed by 3e-6 (1e-5 clipped) of a signal's peak."""
    scenario = shortened("paper-table-3-2-geophones", 8.0)
    t = np.arange(0.0, 8.0 + 5e-4, 1e-3)
    names = tuple(a.name for a in scenario.actuators)
    forces = np.zeros((len(names), t.size))
    forces[names.index("z1")] = 300.0 * np.sin(2 * np.pi * 7.0 * t)
    forces[names.index("x2")] = amplitude * np.sin(2 * np.pi * 3.0 * t + 0.3)
    history = ForceHistory(t, forces, names)
    sim = Simulator(scenario)
    start, end = sim.equilibria(sim.parameters)
    method = sim.method_for(max(start.max_frequency, end.max_frequency), actuated=True)
    reference = sim.run_method(sim.parameters, start, end, Method(2 * method.substeps), forces=history)
    assert worst(sim.run(forces=history), reference) < 1e-7


def test_a_controlled_run_of_lagged_actuators_equals_a_converged_one():
    """A skyhook at 2 kHz: its command changes at every tick, each change a transient of the 200 Hz lag."""
    scenario = shortened("paper-table-3-2-geophones", 8.0)
    ctrl = design_controller(scenario, "skyhook", 2000.0, search=False)
    assert worst(Simulator(scenario).run(controller=ctrl), Refined(scenario).run(controller=ctrl)) < 1e-7


def test_the_lags_windowed_sums_are_their_closed_forms():
    """A step of the command (a repeated time) and a ramp, over 400 time constants (eight windows): the force
    ``u (1 - e^(-t/tau))`` and ``k (t - tau (1 - e^(-t/tau)))``."""
    scenario = load_scenario("paper-table-3-2-geophones")
    tau = 1.0 / (2 * math.pi * 200.0)
    t = np.concatenate([[0.0], np.linspace(0.0, 400 * tau, 20001)])
    command = np.zeros((t.size, len(scenario.actuators)))
    command[1:, 0] = 100.0  # a step at t = 0
    command[:, 1] = 1e3 * t  # a ramp, 1000 N/s: under 500 N for 400 tau
    out = applied_forces(scenario, command, t)
    np.testing.assert_allclose(out[1:, 0], 100.0 * (1 - np.exp(-t[1:] / tau)), rtol=0, atol=1e-11)
    np.testing.assert_allclose(out[:, 1], 1e3 * (t - tau * (1 - np.exp(-t / tau))), rtol=0, atol=1e-10)


@pytest.fixture(scope="module")
def pneumatic():
    scenario = shortened("paper-table-3-2-pneumatic", 10.0)
    sim = Simulator(scenario)
    start, end = sim.equilibria(sim.parameters)
    return sim, start, end


def test_a_pneumatic_run_equals_a_converged_one(pneumatic):
    """The valves open and close nine times in the run: DOP853 steps across those kinks of the flow strayed by
    7.5e-4 of the peak of z from a converged run; ending there, every output is within 1e-7 of its peak."""
    sim, start, end = pneumatic
    reference = sim.run_method(sim.parameters, start, end, Method(64))
    assert worst(sim.run(), reference) < 1e-7


def test_the_steps_end_where_a_valve_switches(pneumatic):
    """The located switches: a sensor height at its dead band's edge, and a step ending there."""
    sim, start, end = pneumatic
    method = sim.method_for(max(start.max_frequency, end.max_frequency))
    plan, out = dense_run(sim, method, sim.parameters, start, None)
    switches = ValveSwitches.of(sim.scenario, sim.layout, sim.parameters)
    assert switches is not None
    times = switches.times(plan, out[3])
    assert times.size >= 4
    heights = np.abs(sensor_heights(sim.scenario, DenseStepper.states_at(plan, out[3], times)))
    edge = np.min(np.abs(heights - 2e-5), axis=0)  # every group's dead band is 20 µm
    assert np.max(edge) < 1e-13
    ends = plan.start[: plan.steps] + plan.length[: plan.steps]
    assert np.max(np.min(np.abs(ends[None, :] - times[:, None]), axis=1)) < 1e-9


def test_a_pneumatic_batch_equals_its_single_runs(pneumatic):
    """Runs side by side end their steps on every run's switches: the same peaks as the runs alone."""
    sim, _, _ = pneumatic
    batch = sim.run_batch([0.8, 1.3], [1.0, 2.0], workers=1)
    for i, (k, c) in enumerate([(0.8, 1.0), (1.3, 2.0)]):
        single = sim.run(p=sim.scaled_parameters(k, c))
        peaks = np.array([single.settling[s].peak for s in single.signal_names])
        np.testing.assert_allclose(batch.peak[i], peaks, rtol=1e-7)
