"""The free motion after a run's end (:mod:`isolator.simulation.free_tail`) for a scenario's run: with the
pneumatic table's valves, whose dead band the linear model about the final rest takes as shut."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from isolator.model.equilibrium import Equilibrium
from isolator.model.variants import Model
from isolator.scenario.definitions import Scenario
from isolator.simulation.free_tail import FreeTail, free_tails
from isolator.simulation.leveling import valve_note

__all__ = ["run_tail", "run_tails"]


def run_tail(scenario: Scenario, model: Model, p: np.ndarray, start: Equilibrium, end: Equilibrium | None,
             last: np.ndarray, end_time: float) -> tuple[FreeTail | None, str]:
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

    Returns
    -------
    tail : FreeTail or None
        None when there is no final rest, or a valve still moves air at the end (the linear model about
        the rest, valves shut, does not hold then; the run must be seen settled).
    note : str
        Pneumatic tables with valves: where their sensors come to rest against the dead bands ("" else).
    """
    return run_tails(scenario, model, np.asarray(p)[None], [start], [end], np.asarray(last)[None], end_time)[0]


def run_tails(scenario: Scenario, model: Model, params: np.ndarray, starts: Sequence[Equilibrium],
              ends: Sequence[Equilibrium | None], last: np.ndarray, end_time: float
              ) -> list[tuple[FreeTail | None, str]]:
    """:func:`run_tail` of several runs (``params``, ``last`` stacked (runs, ...)), their Jacobians at once."""
    out: list[tuple[FreeTail | None, str]] = [(None, "")] * len(starts)
    rows = [k for k, e in enumerate(ends) if e is not None and np.all(np.isfinite(last[k]))]
    if not rows:
        return out
    chosen = [ends[k] for k in rows]
    tails = free_tails(model, params[rows], np.array([e.state for e in chosen]),  # type: ignore[union-attr]
                       np.array([e.positions for e in chosen]),  # type: ignore[union-attr]
                       np.array([starts[k].state for k in rows]), last[rows], end_time)
    for k, tail in zip(rows, tails, strict=True):
        if not scenario.is_pneumatic:
            out[k] = (tail, "")
            continue
        active, note = valve_note(scenario, model.layout.names, params[k], tail.rest, last[k])
        out[k] = (None, "") if active else (tail, note)
    return out
