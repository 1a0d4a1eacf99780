"""Where the carriages may be parked: their travel, the range their profiles cover over the run or, with a
``[sequence]``, the range of its configurations (``docs/scenario-format.md``, "Additions to the budget and the
FMU (trust round 4)"). Commands that park the table (``isolator budget --position``) check positions against
it with :func:`check_travel`."""

from __future__ import annotations

import math

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.definitions import Scenario

__all__ = ["carriage_travel", "check_travel"]

#: relative slack of the travel's ends (a position printed and typed back)
_SLACK = 1e-9


def carriage_travel(scenario: Scenario) -> np.ndarray:
    """Each carriage's travel [m], shape (carriages, 2): least and greatest position of its profile over the run
    (to its stop when it stops later), or of the ``[sequence]``'s configurations (its start and every step's
    target)."""
    names = [c.name for c in scenario.carriages]
    if not names:
        return np.zeros((0, 2))
    if scenario.sequence is not None:
        q = scenario.sequence.configurations(names)
        return np.column_stack([q.min(axis=0), q.max(axis=0)])
    t_end = scenario.simulation.duration
    if math.isfinite(scenario.stop_time):
        t_end = max(t_end, scenario.stop_time)
    return np.array([c.profile.position_range(t_end) for c in scenario.carriages], dtype=float).reshape(-1, 2)


def check_travel(scenario: Scenario, positions: np.ndarray, key: str = "positions") -> None:
    """Refuse carriage positions [m] (one per carriage) beyond the carriages' travel (:func:`carriage_travel`).

    Raises
    ------
    ParameterError
        ``positions.x-stage: 0.75 m is beyond the carriage's travel, -0.7 to 0.7 m (its profile's range)``:
        the first carriage out of its travel, naming it and its travel.
    """
    travel = carriage_travel(scenario)
    q = np.asarray(positions, dtype=float).ravel()
    for i, carriage in enumerate(scenario.carriages):
        low, high = travel[i]
        slack = _SLACK * max(1.0, high - low, abs(low), abs(high))
        if not low - slack <= q[i] <= high + slack:
            what = "the [sequence]'s start and targets" if scenario.sequence is not None else "its profile's range"
            raise ParameterError(f"{key}.{carriage.name}: {q[i]:.6g} m is beyond the carriage's travel, "
                                 f"{low:.6g} to {high:.6g} m ({what})")
