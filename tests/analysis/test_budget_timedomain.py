"""The error budget against long time-domain simulations (issue 32): the RMS it predicts at a point is the RMS
of that point's displacement in a run of the exact model driven by a sampled random signal of the same
spectrum, within the run's statistical error.

The statistical error of a mean square over ``T`` seconds of a Gaussian process with one-sided PSD ``G`` is
``1 / sqrt(T B)`` relative, ``B = (int G)^2 / int G^2`` the process's effective bandwidth (from the budget's
own spectrum); the RMS's is half that. The tests take the larger of that and the batch-means estimate (the
spread of the mean squares of sixteen equal pieces of the record), check that the two agree within a factor of
three (so the error bars are themselves right; 15 degrees of freedom leave that to chance with probability
~1e-5), and assert each axis within 3 sigma.
"""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import numpy as np
import pytest

from controllers.feedback import design_controller
from isolator import Simulator, scenario_from_dict, simulate
from isolator.analysis.budget import ErrorBudget, error_budget
from isolator.analysis.budget.loop import closed_loop_poles
from isolator.analysis.linear import linearise
from isolator.scenario.random_sources import SpectralDensity
from isolator.scenario.reader import bundled_scenarios
from isolator.simulation.actuation import ForceHistory
from isolator.simulation.sensor_noise import shaped_noise
from sampled_loops import RATE, geophone_data

#: the floor's velocity PSD on each axis [(m/s)^2/Hz] at FLOOR_F [Hz]: flat, then falling, zero outside
FLOOR_F = (1.0, 10.0, 100.0)
FLOOR_V = {"x": (1e-12, 1e-12, 1e-14), "y": (2e-12, 2e-12, 2e-14), "z": (4e-12, 1e-12, 1e-13)}
#: a geophone's noise [(m/s)^2/Hz]: falling as f^-2 to 20 Hz, flat above, zero below 2 Hz
GEOPHONE = {"frequency": [2.0, 20.0, 900.0], "value": [1e-16, 1e-18, 1e-18]}
#: a random force's PSD [N^2/Hz]: flat to 10 Hz, then falling, zero outside 1-60 Hz
FORCE = {"frequency": [1.0, 10.0, 60.0], "value": [1.0, 1.0, 0.01]}
POINTS = [{"name": "probe", "position": [0.6, 0.3, 0.5]}, {"name": "corner", "position": [-1.0, -0.5, 0.15]}]
#: pieces of a record for the batch-means error (each 12 s or more, many correlation times)
BATCHES = 16


def _parked(name: str) -> dict:
    data = tomllib.loads(Path(bundled_scenarios()[name]).read_text())
    for c in data["carriages"]:
        start = c["profile"]["start"]
        c["profile"] = {"type": "samples", "t": [0.0, 0.5], "q": [start, start]}
    return data


def _warm_up(poles: np.ndarray) -> float:
    """[s]: eight time constants of the slowest of the continuous ``poles`` [1/s] (a transient from the start
    down to 3e-4 of itself, the variance of a run started at rest within 1e-7 of the stationary one)."""
    return 8.0 / float(np.min(-np.asarray(poles).real))


def _check(budget: ErrorBudget, point: str, t: np.ndarray, motion: np.ndarray, warm: float) -> list[str]:
    """Each axis of ``motion`` (3, N) [m] after ``warm`` against the budget within 3 sigma; the failures."""
    keep = t >= warm
    duration = t[keep][-1] - t[keep][0]
    failures = []
    for j, axis in enumerate("xyz"):
        x = motion[j, keep]
        square = np.mean(x**2)
        pieces = np.array([np.mean(p**2) for p in np.array_split(x, BATCHES)])
        batch = 0.5 * pieces.std(ddof=1) / np.sqrt(BATCHES) / square
        psd = budget.total_psd[budget.points.index(point), j]
        bandwidth = np.trapezoid(psd, budget.frequency) ** 2 / np.trapezoid(psd**2, budget.frequency)
        spectral = 0.5 / np.sqrt(duration * bandwidth)
        assert 1 / 3 < batch / spectral < 3.0, (point, axis, batch, spectral)
        sigma = max(batch, spectral)
        assert sigma < 0.04, (point, axis, sigma)  # the record is long enough for a sharp check
        predicted = budget.value(point, axis)
        error = np.sqrt(square) / predicted - 1
        if abs(error) > 3 * sigma:
            failures.append(f"{point}:{axis}: simulated {np.sqrt(square):.4g} m, budget {predicted:.4g} m, "
                            f"{error:+.1%} ({error / sigma:+.1f} sigma of {sigma:.1%})")
    return failures


def test_the_floor_budget_is_the_rms_of_a_simulated_random_floor():
    """The paper's Table 3.2, carriages parked, its floor moving on x, y and z as samples of a Gaussian signal
    with the floor spectrum's displacement PSD (velocity PSD over (2 pi f)^2, FFT synthesis at 1 kHz): 210 s
    of the exact model, two points, every axis."""
    duration, rate = 210.0, 1000.0
    data = _parked("paper-table-3-2")
    data["points"] = POINTS
    data["ground"] = {"spectrum": {"kind": "psd", "frequency": list(FLOOR_F), **{a: list(v) for a, v in
                                                                                 FLOOR_V.items()}}}
    spectrum = scenario_from_dict(data).ground.spectrum
    budget = error_budget(scenario_from_dict(data))
    t = np.arange(round(duration * rate) + 1) / rate
    rng = np.random.default_rng(11)
    grid = np.geomspace(0.5, 200.0, 2001)
    for axis, values in FLOOR_V.items():
        # a power law between the same corners: the log-log table of the displacement is exact
        displacement = SpectralDensity(tuple(v / (2 * np.pi * f) ** 2 for v, f in zip(values, FLOOR_F, strict=True)),
                                       FLOOR_F)
        np.testing.assert_allclose(displacement(grid) * (2 * np.pi * grid) ** 2, spectrum.velocity_psd(axis, grid),
                                   rtol=1e-12)
        q = shaped_noise(rng.standard_normal(t.size), displacement, rate)
        data["ground"][axis] = {"type": "samples", "t": t.tolist(), "q": q.tolist()}
    data["simulation"] = {"duration": duration, "sample_rate": rate}
    scenario = scenario_from_dict(data)
    run = simulate(scenario)
    warm = _warm_up(linearise(scenario).eigenvalues)
    assert warm < 10.0
    failures = [f for p in budget.points for f in _check(budget, p, run.t, run.point(p), warm)]
    assert not failures, failures


@pytest.mark.parametrize("method", ["skyhook", "lqg"])
def test_the_sensor_noise_budget_is_the_rms_of_a_noisy_closed_loop_run(method):
    """The geophone table, carriages parked, no other source: its twelve geophones with a sloped
    ``noise_psd``, a controller designed as ``isolator controller`` does at 2 kHz; 300 s in the compiled
    loop with ``noise=True`` against the closed-loop budget with only the sensors' noise."""
    data = geophone_data(duration=300.0)
    data["points"] = POINTS[:1]
    for sensor in data["sensors"]:
        del sensor["noise"]
        sensor["noise_psd"] = GEOPHONE
    scenario = scenario_from_dict(data)
    controller = design_controller(scenario, method, RATE)
    budget = error_budget(scenario, controller)
    assert set(budget.sources) == {f"sensor:{s.name}" for s in scenario.sensors}
    run = Simulator(scenario).run(controller=controller, noise=True, seed=3)
    warm = _warm_up(closed_loop_poles(linearise(scenario), controller))
    assert warm < 10.0
    failures = _check(budget, "probe", run.t, run.point("probe"), warm)
    assert not failures, failures


def test_the_force_and_actuator_noise_budget_is_the_rms_of_a_run_with_those_forces():
    """The active Table 3.2 (actuators without lag or limit), carriages parked: a ``[[disturbances]]`` force
    and the noise of actuator z1 against 200 s of the exact model with both applied as sampled forces (1 kHz
    samples of the two densities, the disturbance by an extra actuator at its point along its line). The
    actuator's noise acts after its lag, so a lag on z1 changes nothing in the budget."""
    duration, rate = 200.0, 1000.0
    data = _parked("paper-table-3-2-active")
    data["points"] = POINTS[:1]
    for act in data["actuators"]:
        act.pop("bandwidth", None)
        act["max_force"] = 1e6
    push = {"name": "push", "position": [0.9, -0.4, 0.15], "direction": [0.6, 0.0, 0.8], "psd": FORCE}
    budgeted = copy.deepcopy(data)
    budgeted["disturbances"] = [push]
    budgeted["actuators"][2]["noise_psd"] = FORCE
    budget = error_budget(scenario_from_dict(budgeted))
    assert budget.sources == ("force:push", "actuator:z1")
    budgeted["actuators"][2]["bandwidth"] = 5.0
    lagged = error_budget(scenario_from_dict(budgeted))
    for axis in "xyz":
        assert lagged.value("probe", axis, "actuator:z1") == pytest.approx(budget.value("probe", axis,
                                                                                        "actuator:z1"), rel=1e-9)
    data["actuators"].append({"name": "push", "position": push["position"], "direction": push["direction"],
                              "max_force": 1e6})
    data["simulation"] = {"duration": duration, "sample_rate": rate}
    scenario = scenario_from_dict(data)
    names = tuple(a.name for a in scenario.actuators)
    t = np.arange(round(duration * rate) + 1) / rate
    rng = np.random.default_rng(5)
    density = SpectralDensity(tuple(FORCE["value"]), tuple(FORCE["frequency"]))
    forces = np.zeros((len(names), t.size))
    for name in ("z1", "push"):
        forces[names.index(name)] = shaped_noise(rng.standard_normal(t.size), density, rate)
    run = Simulator(scenario).run(forces=ForceHistory(t, forces, names))
    failures = _check(budget, "probe", run.t, run.point("probe"), _warm_up(linearise(scenario).eigenvalues))
    assert not failures, failures
