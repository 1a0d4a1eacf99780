"""The peaks and settling instants computed in the compiled loop (``cpp/dense_metrics.cpp``) are those of
the numpy functions of :mod:`isolator.simulation.dense_metrics` (the fallback without a compiler), run on
the same dense output: one run and four lanes of differing designs, bands of an own fraction and of fixed
half-widths, a hold that leaves signals unsettled, a carriage that never stops, a diverged lane."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from isolator import Simulator, load_scenario
from isolator.simulation.band import Band
from isolator.simulation.dense_metrics import DenseRuns, dense_metrics
from isolator.simulation.stepping import dense_stepper, signal_width


@pytest.fixture(scope="module")
def runs():
    """Four designs of the Table 3.2 case stepped side by side (stiffness x0.6-1.8, damping x0.5-3)."""
    sim = Simulator(load_scenario("paper-table-3-2"))
    nominal, names = sim.parameter_vector(None), sim.layout.names
    stiff = np.array([".stiffness." in n for n in names])
    damp = np.array([".damping." in n for n in names])
    params = np.array([nominal * np.where(stiff, k, 1.0) * np.where(damp, c, 1.0)
                       for k, c in ((0.6, 0.5), (1.0, 1.0), (1.4, 3.0), (1.8, 0.8))])
    rests = [sim.equilibria(p) for p in params]
    method = sim.method_for(max(max(s.max_frequency, e.max_frequency) for s, e in rests))
    plan = method.plan.probes_only()
    x0 = np.array([s.state for s, _ in rests])
    final = np.array([sim.signals(e.state[None, :], s)[:, 0] for s, e in rests])
    stepper = dense_stepper(sim.model, 4)
    slots, peaks, deviations, polys = stepper.run_slots(x0, plan, sim.plan_inputs(method, params[0]), params, x0,
                                                        with_states=True, final=final)
    dense = DenseRuns(plan, slots, peaks, deviations, polys, x0, sim.model.variant.signals, signal_width(sim.model),
                      stepper.driver)
    assert dense.compiled is not None
    return sim, dense, final


def _both(dense: DenseRuns, *args):
    compiled = dense_metrics(dense, *args)
    numpy = dense_metrics(dataclasses.replace(dense, compiled=None), *args)
    return compiled, numpy


def _same(compiled, numpy, rtol=1e-12):
    for got, want in zip(compiled, numpy, strict=True):
        np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
        np.testing.assert_allclose(got, want, rtol=rtol, atol=1e-15, equal_nan=True)


@pytest.mark.parametrize("band", [Band(), Band("own", 0.02), Band("absolute", None, None, (2e-6, 5e-7, 2e-8,
                                                                                             2e-6, 1e-5, 3e-8))])
def test_four_lanes_equal_numpy(runs, band):
    sim, dense, final = runs
    compiled, numpy = _both(dense, final, sim.stop_time, band, np.zeros(4))
    _same(compiled, numpy)
    assert np.count_nonzero(np.isfinite(compiled[1])) >= 20  # most signals settle: not a comparison of NaNs
    assert np.all(compiled[0] > 0)


def test_a_hold_longer_than_the_tail_leaves_signals_unsettled_as_numpy(runs):
    sim, dense, final = runs
    short = dense_metrics(dense, final, sim.stop_time, Band(), np.zeros(4))[2]
    hold = np.full(4, float(np.median(short)))  # about half the signals were last outside later than this
    compiled, numpy = _both(dense, final, sim.stop_time, Band(), hold)
    _same(compiled, numpy)
    assert 0 < np.count_nonzero(np.isnan(compiled[1])) < 24


def test_no_stop_gives_peaks_only(runs):
    _, dense, _ = runs
    compiled, numpy = _both(dense, None, np.inf, Band(), np.zeros(4))
    _same(compiled, numpy)
    assert np.all(np.isnan(compiled[1]))


def test_a_diverged_lane_leaves_the_others_measured(runs):
    sim, dense, final = runs
    peaks = dense.peaks.copy()
    peaks[100, 2, 3] = np.nan  # lane 3 diverged
    broken = dataclasses.replace(dense, peaks=peaks)
    got = dense_metrics(broken, final, sim.stop_time, Band(), np.zeros(4))
    want = dense_metrics(dense, final, sim.stop_time, Band(), np.zeros(4))
    assert np.isnan(got[0][3, 2])
    assert np.all(np.isnan(got[1][3]))
    _same([g[:3] for g in got], [w[:3] for w in want], rtol=0.0)


def test_one_run_equals_numpy():
    sim = Simulator(load_scenario("paper-table-3-2"), "paper")
    p = sim.parameter_vector(None)
    start, end = sim.equilibria(p)
    method = sim.method_for(max(start.max_frequency, end.max_frequency))
    final = sim.signals(end.state[None, :], start)[:, 0]
    stepper = dense_stepper(sim.model)
    raw, peaks, deviations, polys = stepper.run_slots(start.state, method.plan, sim.plan_inputs(method, p), p,
                                                      start.state, with_states=True, final=final)
    dense = DenseRuns(method.plan, raw[..., None], peaks[..., None], deviations[..., None], polys[..., None],
                      start.state[None, :], sim.model.variant.signals, signal_width(sim.model), stepper.driver)
    compiled, numpy = _both(dense, final[None, :], sim.stop_time, Band(), np.zeros(1))
    _same(compiled, numpy)
    assert np.count_nonzero(np.isfinite(compiled[1])) >= 4


@pytest.mark.parametrize("lanes", [1, 8])
def test_the_loop_writes_the_output_samples_as_the_slots_hold_them(lanes):
    """The signals at the output samples, written by the compiled loop in a response's layout (6, samples),
    are the slots ``plan.sample_slots`` picks out, bit for bit, and the start's column is left alone."""
    sim = Simulator(load_scenario("paper-table-3-2"))
    p = sim.parameter_vector(None)
    start, end = sim.equilibria(p)
    method = sim.method_for(max(start.max_frequency, end.max_frequency))
    stepper = dense_stepper(sim.model, lanes)
    x0 = np.tile(start.state, (lanes, 1)) if lanes > 1 else start.state
    pp = np.tile(p, (lanes, 1)) if lanes > 1 else p
    shape = (6, method.plan.sample_slots.size + 1) + ((lanes,) if lanes > 1 else ())
    samples = np.full(shape, 7.0)
    raw = stepper.run_slots(x0, method.plan, sim.plan_inputs(method, p), pp, x0, samples=samples)[0]
    picked = np.moveaxis(raw[method.plan.sample_slots], 0, 1)
    np.testing.assert_array_equal(samples[:, 1:], picked)
    assert np.all(samples[:, 0] == 7.0)
    with pytest.raises(ValueError, match="samples"):
        stepper.run_slots(x0, method.plan, sim.plan_inputs(method, p), pp, x0, samples=samples[:, :-1])


def test_a_states_signals_from_the_loop_equal_numpys():
    """A run's final signals come from the compiled loop's evaluation: numpy's ``table_signals`` (written apart
    from the casadi expression the loop compiles) gives the same numbers to round-off, for a tilted state too."""
    sim = Simulator(load_scenario("paper-table-3-2"))
    start, end = sim.equilibria(sim.parameter_vector(None))
    stepper = dense_stepper(sim.model)
    tilted = end.state.copy()
    tilted[3:7] = [np.cos(0.01), 0.3 * np.sin(0.01), -0.5 * np.sin(0.01), np.sqrt(0.66) * np.sin(0.01)]
    for state in (end.state, tilted):
        got = stepper.signal_values(state, start.state)
        want = sim.signals(state[None, :], start)[:, 0]
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-18)
    assert np.max(np.abs(stepper.signal_values(tilted, start.state)[3:])) > 5e-3  # the rotation is read
