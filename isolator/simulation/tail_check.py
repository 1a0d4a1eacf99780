"""The free motion after a run's end (:mod:`isolator.simulation.free_tail`) for a scenario's run: with the
pneumatic table's valves, whose dead band the linear model about the final rest takes as shut."""

from __future__ import annotations

import numpy as np

from isolator.model.equilibrium import Equilibrium
from isolator.model.variants import Model
from isolator.scenario.definitions import Scenario
from isolator.simulation.free_tail import FreeTail, free_tail
from isolator.simulation.leveling import valve_note

__all__ = ["run_tail"]


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
    if end is None or not np.all(np.isfinite(last)):
        return None, ""
    tail = free_tail(model, p, end.state, end.positions, start.state, last, end_time)
    if not scenario.is_pneumatic:
        return tail, ""
    active, note = valve_note(scenario, model.layout.names, p, tail.rest, last)
    return (None, "") if active else (tail, note)
