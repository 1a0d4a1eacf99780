"""Issue 36, item 2: the free-motion judgement of a batch made cheap without changing a number. The runs'
decompositions side by side (``FreeMotions``), a bound that shows a signal inside its band only where the
full verdict finds it inside, a run's ``FreeTail`` built only when that bound cannot settle it, and the
Jacobians compiled to compute as casadi's evaluator does."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from isolator import Simulator, load_scenario
from isolator.numerics.dop853 import DenseStepper
from isolator.simulation import free_tail
from isolator.simulation.settling import Band, signal_bands
from isolator.simulation.tail_check import RunTails, run_tails


def _simulator(duration: float) -> Simulator:
    scenario = load_scenario("paper-table-3-2")
    return Simulator(dataclasses.replace(scenario, simulation=dataclasses.replace(scenario.simulation,
                                                                                    duration=duration)))


def _ends(sim: Simulator, params: np.ndarray) -> tuple[list, list, np.ndarray, float, np.ndarray]:
    """Each run's rests, its state at the end and its peaks (by single runs)."""
    starts, ends = sim.equilibria_of(params)
    last, peaks, end = [], [], 0.0
    for p in params:
        run = sim.run(p=p)
        last.append(run.states[-1])
        peaks.append([run.settling[s].peak for s in run.settling])
        end = float(run.t[-1])
    return starts, ends, np.array(last), end, np.array(peaks)


@pytest.mark.parametrize("duration", [9.0, 10.0, 12.0])
def test_the_bound_shows_inside_only_signals_the_verdict_finds_inside(duration):
    sim = _simulator(duration)
    rng = np.random.default_rng(5)
    params = sim.scaled_parameter_sets(rng.uniform(0.5, 2.0, 12), rng.uniform(0.3, 4.0, 12))
    starts, ends, last, end, peaks = _ends(sim, params)
    bands = np.maximum(signal_bands(Band.from_settling(sim.scenario.settling), peaks), 1e-300)
    tails = RunTails.of(sim.scenario, sim.model, params, starts, ends, last, end)
    inside = tails.inside(bands)
    exact = run_tails(sim.scenario, sim.model, params, starts, ends, last, end)
    for k, (tail, _) in enumerate(exact):
        verdict = tail.judge(bands[k])
        assert not np.any(inside[k] & verdict.leaves), k  # never inside where the free motion leaves
        assert not np.any(inside[k] & (verdict.excess > 0.0)), k
        built = tails.get(k)[0]  # the lazily built tail is run_tails' own, number for number
        np.testing.assert_array_equal(built.weights, tail.weights)
        np.testing.assert_array_equal(built.rates, tail.rates)
    if duration == 12.0:  # runs that settled long before their end are shown inside without a FreeTail
        assert inside.all(axis=1).mean() > 0.8
    else:  # some signals are still moving at the end: the bound must leave them to the verdict
        assert not inside.all()


def test_the_compiled_jacobians_are_casadis_evaluators_bit_for_bit():
    sim = Simulator(load_scenario("paper-table-3-2"))
    params = sim.scaled_parameter_sets(np.linspace(0.5, 2.0, 7), np.linspace(0.5, 4.0, 7))
    _, ends = sim.equilibria_of(params)
    states = np.array([e.state for e in ends])
    inputs = np.array([sim.layout.rest_inputs(e.positions) for e in ends])
    state_jacobian, _ = free_tail._jacobians(sim.model)
    compiled = state_jacobian(states, inputs, params)[0]
    for k in range(len(ends)):
        evaluator = np.asarray(sim.model.state_jacobian(states[k], inputs[k], params[k]))
        np.testing.assert_array_equal(compiled[k], evaluator)


def test_a_batch_builds_a_free_tail_only_for_runs_the_bound_cannot_settle(monkeypatch):
    sim = Simulator(load_scenario("paper-table-3-2"))
    built = []
    original = free_tail.FreeMotions.tail
    monkeypatch.setattr(free_tail.FreeMotions, "tail", lambda self, k: built.append(k) or original(self, k))
    rng = np.random.default_rng(2)
    result = sim.run_batch(rng.uniform(0.5, 2.0, 40), rng.uniform(0.5, 4.0, 40), workers=1)
    missing = int(np.isnan(result.settling_time).any(axis=1).sum())
    assert missing <= len(built) < 40 // 4  # the runs without a time get their reasons; few others


def test_the_end_states_of_a_pack_are_each_lanes_own():
    """The states at the end of four lanes evaluated at once equal each lane's own evaluation."""
    sim = Simulator(load_scenario("paper-table-3-2"))
    plan = sim.method_for(1.0e3).plan
    rng = np.random.default_rng(0)
    polys = rng.normal(size=(plan.steps, 8, sim.model.n_states, 4))
    shape = polys.shape
    together = DenseStepper.states_at(plan, polys.reshape(*shape[:2], -1), np.array([plan.end]))[0]
    together = together.reshape(shape[2:]).T
    for lane in range(4):
        np.testing.assert_array_equal(together[lane],
                                      DenseStepper.states_at(plan, polys[..., lane], np.array([plan.end]))[0])


def test_a_batch_run_that_diverges_is_named_at_its_first_non_finite_output_sample(monkeypatch):
    """The batch's loop reads the probes only; a run whose probes go non-finite is stepped again with the output
    samples, for the message naming the first non-finite one, as before."""
    sim = Simulator(load_scenario("paper-table-3-2"))
    original = DenseStepper.run_slots

    def poisoned(self, x0, plan, *args, **kwargs):  # type: ignore[no-untyped-def]
        signals, peaks, deviations, polys = original(self, x0, plan, *args, **kwargs)
        if plan.sample_slots.size:  # the full plan: the samples from the 2001st on are NaN
            signals = signals.copy()
            signals[plan.sample_slots[2000:], :, 0] = np.nan
        else:
            peaks = peaks.copy()
            peaks[300:, :, 0] = np.nan
        return signals, peaks, deviations, polys

    monkeypatch.setattr(DenseStepper, "run_slots", poisoned)
    result = sim.run_batch([1.0], [1.0], workers=1, diverged="record")
    assert result.status.tolist() == ["diverged"]
    assert f"the run diverged: non-finite state at t = {sim.grid.samples[2001]:.4g} s" in result.failures[0]
