"""Issue 43: a simulator keeps the rests of the newest parameter vectors, with the free motion's decomposition
about the final one (:class:`~isolator.simulation.tail_check.KnownRests`), for runs of the same table. What
is kept must be what a fresh solve gives, read-only, forgotten past sixteen tables, and a run that uses it must
equal one that does not, number for number."""

from __future__ import annotations

import numpy as np
import pytest

from isolator import Simulator, load_scenario
from isolator.model.equilibrium import static_equilibria
from isolator.scenario.definitions import SIGNALS
from isolator.simulation.free_tail import RestModes
from isolator.simulation.tail_check import run_tail


@pytest.fixture(scope="module")
def sim() -> Simulator:
    return Simulator(load_scenario("paper-table-3-2"))


def _numbers(response) -> np.ndarray:
    times = [response.settling[k].time for k in SIGNALS]
    return np.concatenate([response.signals.ravel(), [np.nan if t is None else t for t in times],
                           [response.settling[k].peak for k in SIGNALS]])


def test_the_kept_rests_are_a_fresh_solves(sim):
    p = sim.scaled_parameters(1.3, 0.7)
    start, end = sim.equilibria(p)
    first, last = sim._positions
    fresh_start = static_equilibria(sim.model, p[None], first)[0]
    fresh_end = static_equilibria(sim.model, p[None], last)[0]
    for kept, fresh in ((start, fresh_start), (end, fresh_end)):
        np.testing.assert_array_equal(kept.state, fresh.state)
        np.testing.assert_array_equal(kept.eigenvalues, fresh.eigenvalues)
    assert sim.equilibria(p)[0] is start  # kept, not solved again
    assert sim.equilibria(p.copy())[1] is end  # by value, not by the array's identity


def test_the_kept_arrays_cannot_be_changed(sim):
    start, end = sim.equilibria(sim.parameters)
    for array in (start.state, start.pose, end.state, end.eigenvalues):
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 1.0


def test_the_kept_decomposition_gives_the_free_motion_computed_afresh(sim):
    p = sim.scaled_parameters(0.8, 2.0)
    known = sim.known_rests(p)
    start, end = known.start, known.end
    last = end.state + 1e-6 * np.linspace(-1.0, 1.0, end.state.size)  # a run ending off its rest
    kept, _ = run_tail(sim.scenario, sim.model, p, start, end, last, 12.0, known.modes)
    fresh, _ = run_tail(sim.scenario, sim.model, p, start, end, last, 12.0)
    assert kept is not None
    assert fresh is not None
    np.testing.assert_array_equal(kept.rates, fresh.rates)
    np.testing.assert_array_equal(kept.weights, fresh.weights)
    np.testing.assert_array_equal(kept.offset, fresh.offset)
    modes = RestModes.of(sim.model, p[None], end.state[None], end.positions[None], start.state[None])
    np.testing.assert_array_equal(known.modes.vectors, modes.vectors)


def test_a_run_of_a_kept_table_equals_its_first_run_and_past_sixteen_tables_it_is_solved_again(sim):
    p = sim.scaled_parameters(1.1, 1.4)
    first = sim.run(p=p)
    kept = sim.equilibria(p)[0]
    again = sim.run(p=p)
    np.testing.assert_array_equal(_numbers(again), _numbers(first))
    for s in np.linspace(0.9, 1.2, 16):  # sixteen other tables push it out
        sim.equilibria(sim.scaled_parameters(s, 3.0))
    assert sim.equilibria(p)[0] is not kept
    np.testing.assert_array_equal(_numbers(sim.run(p=p)), _numbers(first))


def test_a_table_one_rounding_away_is_another_table(sim):
    p = sim.scaled_parameters(1.05, 1.0)
    q = p.copy()
    q[np.argmax(np.abs(q))] = np.nextafter(q[np.argmax(np.abs(q))], np.inf)
    assert sim.equilibria(q)[0] is not sim.equilibria(p)[0]


def test_a_second_run_of_a_table_decomposes_nothing_again(sim, monkeypatch):
    calls = []
    real = RestModes.of.__func__

    def counted(cls, *args):
        calls.append(args)
        return real(cls, *args)

    monkeypatch.setattr(RestModes, "of", classmethod(counted))
    p = sim.scaled_parameters(0.95, 1.7)
    sim.run(p=p)
    assert len(calls) == 1  # the first run decomposes the final rest
    sim.run(p=p)
    assert len(calls) == 1  # the second reuses it
    sim.run(p=sim.scaled_parameters(0.96, 1.7))
    assert len(calls) == 2
