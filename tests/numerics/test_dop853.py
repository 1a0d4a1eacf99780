"""The DOP853 method and its steppers.

Independent checks: the tableau against the exact solution of a harmonic
oscillator (numpy only, no casadi), step plans against their definition, the
compiled C++ loop (one run, or four in SIMD lanes) against casadi's evaluator
of the same steps written as a casadi graph, and a mapped function against
one call per row.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm

from conftest import asymmetric_3d_dict, base_dict
from isolator import (
    Simulator,
    scenario_from_dict,
)
from isolator.model.variants import EXACT
from isolator.numerics.dop853 import STAGES, TAIL, dop853_tableau, step_plan
from isolator.numerics.native import MappedFunction


def _dop853_step(a: np.ndarray, y0: np.ndarray, h: float, fractions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One DOP853 step of y' = a y in numpy from the tableau: the new state and the dense output."""
    tab = dop853_tableau()
    k = np.zeros((STAGES, y0.size))
    for i in range(STAGES):
        k[i] = a @ (y0 + h * tab.a[i, :i] @ k[:i])
    y1 = y0 + h * tab.weights @ k[: tab.end]
    powers = fractions[None, :] ** np.arange(1, tab.dense.shape[1] + 1)[:, None]
    dense = y0[:, None] + h * k.T @ tab.dense @ powers
    return y1, dense


def test_the_tableau_is_eighth_order_with_a_seventh_order_dense_output():
    omega = 2 * np.pi * 5.0
    a = np.array([[0.0, 1.0], [-(omega**2), -0.02 * omega]])
    y0 = np.array([1.0, 0.0])
    s = np.linspace(0.05, 1.0, 20)
    step_errors, dense_errors = [], []
    for h in (0.02, 0.01):
        y1, dense = _dop853_step(a, y0, h, s)
        exact = np.stack([expm(a * h * f) @ y0 for f in s], axis=1)
        step_errors.append(np.abs(y1 - expm(a * h) @ y0).max())
        dense_errors.append(np.abs(dense - exact).max())
    # local errors: h^9 for the step, h^8 for the interpolant
    assert step_errors[0] / step_errors[1] > 2**8.5
    assert dense_errors[0] / dense_errors[1] > 2**7.5
    # the interpolant ends on the step
    _, end = _dop853_step(a, y0, 0.02, np.array([1.0]))
    assert np.allclose(end[:, 0], _dop853_step(a, y0, 0.02, s)[0], rtol=1e-12, atol=1e-12)


def test_the_step_plan_keeps_breakpoints_on_step_edges_and_reads_every_sample_once():
    samples = np.arange(0, 2001) / 1000.0
    breakpoints = np.array([0.2, 0.2505, 1.0, 1.7])
    plan = step_plan(samples, breakpoints, 0.03)
    real = slice(0, plan.steps)
    ends = plan.start[real] + plan.length[real]
    assert plan.start.size % TAIL == 0
    assert np.all(plan.length[real] <= 0.03 + 1e-12)
    assert np.all(plan.length[plan.steps:] == 0.0)
    for b in breakpoints:  # never strictly inside a step
        assert not np.any((plan.start[real] < b - 1e-12) & (ends > b + 1e-12))
    flat = plan.fraction.ravel()
    assert np.unique(plan.sample_slots).size == samples.size - 1
    owner = plan.sample_slots // plan.per_step
    times = plan.start[owner] + flat[plan.sample_slots] * plan.length[owner]
    assert np.allclose(times, samples[1:], atol=1e-12)
    assert np.all(flat[plan.sample_slots] > 0)
    unused = np.setdiff1d(np.arange(flat.size), plan.sample_slots)
    assert np.all(flat[unused] == -1.0)
    assert plan.first[0] == 1.0
    assert np.count_nonzero(plan.first[: plan.steps]) == breakpoints.size + 1


def test_a_mapped_function_over_a_part_block():
    import casadi as ca

    x, y = ca.SX.sym("x", 2), ca.SX.sym("y", 3)
    fn = ca.Function("f", [x, y], [ca.vertcat(x[0] * y[2], ca.sin(x[1])), x @ y[:2].T])
    mapped = MappedFunction(fn, "test_mapped_block", block=4)
    xs, ys = np.random.default_rng(2).normal(size=(7, 2)), np.array([1.0, 2.0, 3.0])
    column, matrix = mapped(xs, ys)
    for i in range(7):
        c, m = fn(xs[i], ys)
        assert np.allclose(column[i], np.asarray(c).ravel())
        assert np.allclose(matrix[i], np.asarray(m))


def test_the_stepper_without_a_compiler_gives_the_same_run(monkeypatch):
    import isolator.numerics.native as native
    from isolator.model.signals import signal_function
    from isolator.numerics.dop853 import DenseStepper

    data = base_dict()
    data["simulation"] = {"duration": 2.7, "sample_rate": 500.0}  # the run includes the stop (2.65 s)
    sim = Simulator(scenario_from_dict(data))
    p = sim.parameters
    start, end = sim.equilibria(p)
    method = sim.method_for(max(start.max_frequency, end.max_frequency))
    inputs = sim.plan_inputs(method, p)
    signals = signal_function(EXACT, 13)
    compiled = DenseStepper(sim.model, signals)
    evaluated = DenseStepper(sim.model, signals, compile=False)
    assert compiled.native
    assert not evaluated.native
    a = compiled.run(start.state, method.plan, inputs, p, start.state)
    b = evaluated.run(start.state, method.plan, inputs, p, start.state)
    # the signals at the output samples in a response's layout, filled by either form as its slots hold them
    for stepper in (compiled, evaluated):
        samples = np.zeros((6, method.plan.sample_slots.size + 1))
        slots = stepper.run_slots(start.state, method.plan, inputs, p, start.state, samples=samples)[0]
        np.testing.assert_array_equal(samples[:, 1:], slots[method.plan.sample_slots].T)
    # the same numbers up to rounding (the compiled code is built with -ffast-math)
    assert np.allclose(a[0], b[0], rtol=0, atol=1e-10 * np.abs(a[0]).max())
    assert np.allclose(a[1], b[1], rtol=0, atol=1e-10 * np.abs(a[1]).max())
    # a C compiler but no C++ one: the casadi graph is compiled as C, with a warning
    any_compiler = native.find_compiler
    monkeypatch.setattr(native, "find_compiler",
                        lambda language="c": any_compiler(language) if language == "c" else None)
    with pytest.warns(RuntimeWarning, match=r"no C\+\+ compiler found \(set CXX\)"):
        graph = DenseStepper(sim.model, signals)
    assert not graph.native
    c = graph.run(start.state, method.plan, inputs, p, start.state)
    assert graph.graph is not None
    assert graph.graph.functions(method.plan.per_step, True)[0].native
    assert np.allclose(c[0], b[0], rtol=0, atol=1e-10 * np.abs(a[0]).max())


@pytest.mark.parametrize("kind", ["exact", "paper"])
def test_four_runs_side_by_side_step_like_casadis_evaluator_one_at_a_time(kind):
    from isolator.model.signals import signal_function
    from isolator.numerics.dop853 import DenseStepper

    data = asymmetric_3d_dict()
    data["simulation"] = {"duration": 1.9, "sample_rate": 500.0}  # the run includes the stop (1.8 s)
    sim = Simulator(scenario_from_dict(data), model=kind)
    params = np.array([sim.scaled_parameters(k, c) for k, c in ((0.6, 3.0), (1.0, 1.0), (1.4, 0.5), (2.0, 2.0))])
    starts = [sim.equilibria(p)[0] for p in params]
    method = sim.method_for(max(s.max_frequency for s in starts))  # one plan for all four
    plan, inputs = method.plan, sim.plan_inputs(method, params[0])
    x0 = np.array([s.state for s in starts])
    signals = signal_function(sim.model.variant, sim.model.n_states)
    lanes = DenseStepper(sim.model, signals, lanes=4)
    assert lanes.native
    finals = np.array([[1e-4, -2e-6, 3e-6, 0.0, 1e-5, -1e-6]] * 4) * np.arange(1, 5)[:, None]
    sig, peaks, deviations, polys = lanes.run_slots(x0, plan, inputs, params, x0, with_states=True, final=finals)
    assert sig.shape[-1] == peaks.shape[-1] == deviations.shape[-1] == polys.shape[-1] == 4
    evaluated = DenseStepper(sim.model, signals, compile=False)
    for lane in range(4):
        ref_sig, ref_peaks, ref_deviations, ref_polys = evaluated.run_slots(
            x0[lane], plan, inputs, params[lane], x0[lane], with_states=True, final=finals[lane]
        )
        scale = np.abs(ref_sig[plan.sample_slots]).max()
        assert scale > 1e-6  # the runs move
        assert np.allclose(sig[plan.sample_slots, :, lane], ref_sig[plan.sample_slots], rtol=0, atol=1e-10 * scale)
        assert np.allclose(peaks[..., lane], ref_peaks, rtol=0, atol=1e-10 * scale)
        assert np.allclose(deviations[..., lane], ref_deviations, rtol=0, atol=1e-10 * scale)
        # peaks and deviations are over the probes: 1/8 .. 8/8 of each step
        probes = sig[: plan.steps * plan.per_step, :, lane].reshape(plan.steps, plan.per_step, 6)[:, : plan.probes]
        assert np.allclose(peaks[..., lane], np.abs(probes).max(axis=1), rtol=0, atol=1e-13 * scale)
        assert np.allclose(deviations[..., lane], np.abs(probes - finals[lane]).max(axis=1), rtol=0,
                           atol=1e-13 * scale)
        # the states at the samples (the dense output's high coefficients are sums that cancel)
        ours, theirs = (DenseStepper.states(plan, q) for q in (polys[..., lane], ref_polys))
        assert np.allclose(ours, theirs, rtol=0, atol=1e-9 * np.abs(theirs).max(axis=0))
    # the lanes are the runs: different parameters, different answers
    assert np.abs(sig[plan.sample_slots, :, 0] - sig[plan.sample_slots, :, 3]).max() > 1e-3 * scale
    with pytest.raises(ValueError, match="lanes"):
        lanes.run_slots(x0[0], plan, inputs, params[0], x0[0])


@pytest.fixture(scope="module")
def one_run():
    """A short run of the exact model (one carriage's move) and its compiled single-run stepper."""
    from isolator.model.signals import signal_function
    from isolator.numerics.dop853 import DenseStepper

    data = base_dict()
    data["simulation"] = {"duration": 2.7, "sample_rate": 200.0}
    sim = Simulator(scenario_from_dict(data))
    p = sim.parameters
    start, end = sim.equilibria(p)
    method = sim.method_for(max(start.max_frequency, end.max_frequency))
    stepper = DenseStepper(sim.model, signal_function(EXACT, 13))
    assert stepper.native
    return stepper, method.plan, sim.plan_inputs(method, p), p, start.state, end.state


@settings(max_examples=25, deadline=None)
@given(per=st.integers(1, 21), probes=st.integers(0, 21), used=st.floats(0.0, 1.0), seed=st.integers(0, 2**31))
def test_one_runs_slots_in_vectors_are_each_slots_signals(one_run, per, probes, used, seed):
    """The single-run loop computes its slots' signals several at a time: any pattern of used slots (a step's
    last group part full), with or without probes, gives each used slot the signals of its own state (numpy's,
    from the dense output), the peaks over its probes and the samples in order."""
    from isolator.model.signals import table_signals
    from isolator.numerics.dop853 import DenseStepper

    stepper, plan, inputs, p, x0, rest = one_run
    probes = min(probes, per)
    rng = np.random.default_rng(seed)
    rows = plan.fraction.shape[0]
    fraction = np.where(rng.random((rows, per)) < used, rng.random((rows, per)), -1.0)
    fraction[plan.steps:] = -1.0
    flat = np.flatnonzero((fraction >= 0).ravel())
    samples_at = flat[flat % per >= probes]
    trial = dataclasses.replace(plan, fraction=fraction, sample_slots=samples_at, probes=probes)
    final = stepper.signal_values(rest, x0)
    samples = np.full((6, samples_at.size + 1), np.nan)
    sig, peaks, deviations, polys = stepper.run_slots(x0, trial, inputs, p, x0, with_states=True, final=final,
                                                      samples=samples)
    assert polys is not None
    want = table_signals(DenseStepper.states(dataclasses.replace(trial, sample_slots=flat), polys), x0).T
    scale = max(np.abs(want).max(initial=0.0), 1e-9)
    np.testing.assert_allclose(sig[flat], want, rtol=0, atol=1e-10 * scale)
    np.testing.assert_array_equal(samples[:, 1:], sig[samples_at].T)
    counted = flat[(flat % per < probes) | (probes == 0)]
    for s in range(plan.steps):
        mine = counted[counted // per == s]
        top = np.abs(sig[mine]).max(axis=0, initial=0.0)
        off = np.abs(sig[mine] - final).max(axis=0, initial=0.0)
        np.testing.assert_array_equal(peaks[s], top)
        np.testing.assert_array_equal(deviations[s], off)


def test_a_compiler_error_is_one_line_naming_the_library(tmp_path, monkeypatch):
    from isolator.numerics.native import compiled_library

    monkeypatch.setenv("ISOLATOR_CACHE", str(tmp_path))
    with pytest.raises(RuntimeError, match=r"failed on broken: .*error"):
        compiled_library("broken", "int f( {", language="c++")
    assert not list(tmp_path.glob("*.so"))  # nothing half-built is left
    assert not list(tmp_path.glob("*.cpp"))
