"""The free motion after a run's end (:mod:`isolator.simulation.free_tail`) for a scenario's run: with the
pneumatic table's valves, whose dead band the linear model about the final rest takes as shut."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from isolator.model.equilibrium import Equilibrium
from isolator.model.variants import Model
from isolator.scenario.definitions import Scenario
from isolator.simulation.free_tail import FreeMotions, FreeTail, RestModes, free_tails
from isolator.simulation.leveling import valve_note

__all__ = ["KnownRests", "RunTails", "run_tail", "run_tails"]


def run_tail(scenario: Scenario, model: Model, p: np.ndarray, start: Equilibrium, end: Equilibrium | None,
             last: np.ndarray, end_time: float, modes: RestModes | None = None) -> tuple[FreeTail | None, str]:
    """The free motion after a run's end and what keeps a pneumatic table off its final rest.

    Parameters
    ----------
    scenario : Scenario
    model : Model
    p : ndarray
        Parameter vector.
    start, end : Equilibrium
        The initial and final rests (``end`` None: a carriage never stops).
    last : ndarray (n_states,)
        The run's state at its end.
    end_time : float
        The run's end [s].
    modes : RestModes, optional
        The linear model about ``end`` decomposed (:meth:`RestModes.of` with ``start`` the reference), when the
        caller keeps it (computed here otherwise).

    Returns
    -------
    tail : FreeTail or None
        None when there is no final rest, or a valve still moves air at the end (the linear model about
        the rest, valves shut, does not hold then; the run must be seen settled).
    note : str
        Pneumatic tables with valves: where their sensors come to rest against the dead bands ("" else).
    """
    return run_tails(scenario, model, np.asarray(p)[None], [start], [end], np.asarray(last)[None], end_time, modes)[0]


def run_tails(scenario: Scenario, model: Model, params: np.ndarray, starts: Sequence[Equilibrium],
              ends: Sequence[Equilibrium | None], last: np.ndarray, end_time: float, modes: RestModes | None = None
              ) -> list[tuple[FreeTail | None, str]]:
    """:func:`run_tail` of several runs (``params``, ``last`` stacked (runs, ...)), their Jacobians at once
    (``modes``: those of the runs with a final rest, when the caller has them)."""
    out: list[tuple[FreeTail | None, str]] = [(None, "")] * len(starts)
    rows = [k for k, e in enumerate(ends) if e is not None and np.all(np.isfinite(last[k]))]
    if not rows:
        return out
    chosen = [ends[k] for k in rows]
    tails = free_tails(model, params[rows], np.array([e.state for e in chosen]),  # type: ignore[union-attr]
                       np.array([e.positions for e in chosen]),  # type: ignore[union-attr]
                       np.array([starts[k].state for k in rows]), last[rows], end_time, modes)
    for k, tail in zip(rows, tails, strict=True):
        if not scenario.is_pneumatic:
            out[k] = (tail, "")
            continue
        active, note = valve_note(scenario, model.layout.names, params[k], tail.rest, last[k])
        out[k] = (None, "") if active else (tail, note)
    return out


@dataclass(frozen=True)
class KnownRests:
    """A table's two rests for a scenario's run and, built on first use, the free motion's decomposition about
    the final one: what every run of that table shares, kept by a simulator per parameter vector (their arrays
    made read-only, since runs share them).

    Attributes
    ----------
    model : Model
    p : ndarray
        The parameter vector.
    start, end : Equilibrium
        The initial and final rests (``end`` None: a carriage never stops).
    """

    model: Model
    p: np.ndarray
    start: Equilibrium
    end: Equilibrium | None

    def __post_init__(self) -> None:
        self.p.flags.writeable = False
        for rest in (self.start, self.end):
            for array in () if rest is None else (rest.pose, rest.state, rest.positions, rest.eigenvalues):
                array.flags.writeable = False  # positions may be the simulator's own: read-only there too

    @cached_property
    def modes(self) -> RestModes | None:
        """The linear model about the final rest, decomposed (None without one)."""
        if self.end is None:
            return None
        return RestModes.of(self.model, self.p[None], self.end.state[None], self.end.positions[None],
                            self.start.state[None])


@dataclass(frozen=True)
class RunTails:
    """:func:`run_tails` of a batch's runs, each run's answer built when asked for (:meth:`get`): the runs
    whose signals :meth:`inside` shows inside their bands need none.

    Attributes
    ----------
    has : ndarray (runs,) of bool
        Whether run ``k`` has a free motion to judge by (``get(k)[0]`` is not None).
    motions : FreeMotions or None
        The decompositions of the runs in ``rows`` (None: none, or built eagerly in ``eager``).
    rows : dict of int to int
        Run -> its row in ``motions``.
    eager : list or None
        Every run's answer, built at once (pneumatic tables, whose valves need each rest).
    """

    has: np.ndarray
    motions: FreeMotions | None
    rows: dict[int, int]
    eager: list[tuple[FreeTail | None, str]] | None = None

    @classmethod
    def of(cls, scenario: Scenario, model: Model, params: np.ndarray, starts: Sequence[Equilibrium],
           ends: Sequence[Equilibrium | None], last: np.ndarray, end_time: float) -> RunTails:
        """As :func:`run_tails` takes them."""
        if scenario.is_pneumatic:
            eager = run_tails(scenario, model, params, starts, ends, last, end_time)
            return cls(np.array([tail is not None for tail, _ in eager]), None, {}, eager)
        rows = [k for k, e in enumerate(ends) if e is not None and np.all(np.isfinite(last[k]))]
        has = np.zeros(len(starts), dtype=bool)
        has[rows] = True
        if not rows:
            return cls(has, None, {})
        chosen = [ends[k] for k in rows]
        motions = FreeMotions.of(model, params[rows], np.array([e.state for e in chosen]),  # type: ignore[union-attr]
                                 np.array([e.positions for e in chosen]),  # type: ignore[union-attr]
                                 np.array([starts[k].state for k in rows]), last[rows], end_time)
        return cls(has, motions, {k: j for j, k in enumerate(rows)})

    def get(self, k: int) -> tuple[FreeTail | None, str]:
        """Run ``k``'s entry of :func:`run_tails`."""
        if self.eager is not None:
            return self.eager[k]
        if k not in self.rows or self.motions is None:
            return None, ""
        return self.motions.tail(self.rows[k]), ""

    def inside(self, band: np.ndarray) -> np.ndarray:
        """Which signals (runs, 6) of the runs provably stay inside their bands ``band`` (runs, 6) [m or rad]
        after the end (:meth:`FreeMotions.inside`; False for runs without a free motion, and for pneumatic
        tables, whose answers are built anyway)."""
        out = np.zeros((self.has.size, 6), dtype=bool)
        if self.motions is not None:
            rows = list(self.rows)
            out[rows] = self.motions.inside(np.asarray(band, dtype=float)[rows])
        return out
