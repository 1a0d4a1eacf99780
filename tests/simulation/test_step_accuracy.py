"""The simulator's own steps are as accurate as a converged run: the actuators' lags taken exactly by the RK4
steps of the table's own rule (forces, controllers: lag_stages), the leveling valves' switches as DOP853 step
ends (pneumatic tables); the
lags' windowed sums against their closed forms."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from controllers.feedback import design_controller
from isolator import Simulator, load_scenario
from isolator.numerics.dop853 import DenseStepper
from isolator.scenario.ground import Ground
from isolator.scenario.profiles import SineProfile
from isolator.simulation import simulator as simulator_module
from isolator.simulation.actuation import ForceHistory, applied_forces
from isolator.simulation.lag_steps import lag_stages
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
    """The simulator with four times as many RK4 steps as its rule gives, closed loops included (converged for
    the skyhook below: 4e-11 of the peak from eight times as many)."""

    def substeps_for(self, *args, **kwargs) -> int:
        return 4 * super().substeps_for(*args, **kwargs)


def test_the_step_rule_does_not_resolve_the_lags():
    """The lags cost no step: the rule is the table's eigenvalues and sine drives, forces or not."""
    scenario = load_scenario("paper-table-3-2-geophones")
    assert fastest_rate(scenario, 40.0) == 40.0
    shaken = dataclasses.replace(scenario, ground=Ground(motion={"z": SineProfile(1e-6, 2e3)}))
    assert fastest_rate(shaken, 40.0) == 2e3
    sim = Simulator(scenario)
    assert sim.substeps_for(40.0) == math.ceil(40.0 * 1e-3 / STEP_ANGLE) == 1
    method = sim.method_for(40.0, actuated=True)
    assert method.plan is None
    assert method.substeps == 1


def forced(amplitude: float) -> tuple[object, ForceHistory]:
    """The geophone table (8 s) with two sines sampled at 1 ms and a step, on lagged actuators."""
    scenario = shortened("paper-table-3-2-geophones", 8.0)
    t = np.arange(0.0, 8.0 + 5e-4, 1e-3)
    names = tuple(a.name for a in scenario.actuators)
    forces = np.zeros((len(names), t.size))
    forces[names.index("z1")] = 300.0 * np.sin(2 * np.pi * 7.0 * t)
    forces[names.index("x2")] = amplitude * np.sin(2 * np.pi * 3.0 * t + 0.3)
    forces[names.index("y3")] = np.where(t >= 2.0, 200.0, 0.0)
    return scenario, ForceHistory(t, forces, names)


@pytest.mark.parametrize("amplitude", [400.0, 700.0])  # 700: clipped at the actuator's 500 N inside the steps
def test_a_forced_run_of_lagged_actuators_equals_a_converged_one(amplitude, monkeypatch):
    """Twelve actuators with a 200 Hz lag (0.8 ms) at one RK4 step per millisecond (the table's own rule): every
    output within 1e-6 of its peak of a run with 32 steps per millisecond (converged: 2e-13 from 64). The same
    steps fed the lagged force at the stage times instead of lag_stages' stray by 5e-6 of the peak."""
    scenario, history = forced(amplitude)
    sim = Simulator(scenario)
    start, end = sim.equilibria(sim.parameters)
    assert sim.method_for(max(start.max_frequency, end.max_frequency), actuated=True).substeps == 1
    reference = sim.run_method(sim.parameters, start, end, Method(32), forces=history)
    assert worst(sim.run(forces=history), reference) < 1e-6
    plain = simulator_module.with_forces  # the old rule's step count without it: the lag's rate not followed
    monkeypatch.setattr(simulator_module, "with_forces", lambda *args: (plain(*args)[1],) * 2)
    assert worst(sim.run(forces=history), reference) > 2e-6


def test_a_controlled_run_of_lagged_actuators_equals_a_converged_one():
    """A skyhook at 2 kHz: its command changes at every tick, each change a transient of the 200 Hz lag that one
    RK4 step per tick takes exactly."""
    scenario = shortened("paper-table-3-2-geophones", 8.0)
    ctrl = design_controller(scenario, "skyhook", 2000.0, search=False)
    assert worst(Simulator(scenario).run(controller=ctrl), Refined(scenario).run(controller=ctrl)) < 1e-6


@settings(max_examples=30, deadline=None)
@given(tau=st.floats(1e-5, 1.0), h=st.floats(1e-4, 2e-3), values=st.lists(st.floats(-900.0, 900.0), min_size=4,
                                                                           max_size=4),
       limit=st.one_of(st.none(), st.floats(50.0, 600.0)))
def test_the_stage_forces_carry_the_lags_exact_moments(tau, h, values, limit):
    """The four moments ``int (h - s)^n / n! f ds`` RK4 gives the stages' forces equal those of the lag's exact
    force (a tight ODE solve), the command clipped with its kinks inside the step; the middle and end forces too."""
    f0, u0, um, u1 = values

    def command(s: float) -> float:
        u = u0 + (um - u0) * s / (h / 2) if s <= h / 2 else um + (u1 - um) * (s - h / 2) / (h / 2)
        return u if limit is None else min(max(u, -limit), limit)

    def rates(s, y):
        return [(command(s) - y[0]) / tau] + [(h - s) ** n / math.factorial(n) * y[0] for n in range(4)]

    half = solve_ivp(rates, (0, h / 2), [f0, 0, 0, 0, 0], method="DOP853", rtol=1e-12, atol=1e-12, max_step=h / 400)
    full = solve_ivp(rates, (h / 2, h), half.y[:, -1], method="DOP853", rtol=1e-12, atol=1e-12, max_step=h / 400)
    (b1, b2, b3, b4), (f_half, f_end) = lag_stages(f0, u0, um, u1, h, tau, limit)
    got = [h / 6 * (b1 + 2 * b2 + 2 * b3 + b4), h**2 / 6 * (b1 + b2 + b3), h**3 / 12 * (b1 + b2), h**4 / 24 * b1]
    scale = max(abs(v) for v in values)
    for n in range(4):
        assert abs(got[n] - full.y[n + 1, -1]) <= 1e-8 * scale * h ** (n + 1) / math.factorial(n + 1)
    assert abs(f_half - half.y[0, -1]) <= 1e-8 * scale
    assert abs(f_end - full.y[0, -1]) <= 1e-8 * scale


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
