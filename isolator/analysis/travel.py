"""Where the carriages may be parked: within their travel (:meth:`~isolator.scenario.definitions.Scenario.travel`:
the range their profiles cover over the run or, with a ``[sequence]``, that of its start and targets;
``docs/scenario-format.md``, "Additions to the budget and the FMU (trust round 4)"). Commands that park the table
(``isolator budget --position``) check the positions given with :func:`check_travel`."""

from __future__ import annotations

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.definitions import Scenario

__all__ = ["check_travel"]

#: relative slack of the travel's ends (a position printed and typed back)
_SLACK = 1e-9


def check_travel(scenario: Scenario, positions: np.ndarray, key: str = "positions") -> None:
    """Refuse carriage positions [m] (one per carriage) beyond the carriages' travel
    (:meth:`~isolator.scenario.definitions.Scenario.travel`).

    Raises
    ------
    ParameterError
        ``positions.x-stage: 0.75 m is beyond the carriage's travel, -0.7 to 0.7 m (its profile's range)``:
        the first carriage out of its travel, naming it and its travel.
    """
    travel = scenario.travel()
    q = np.asarray(positions, dtype=float).ravel()
    for i, carriage in enumerate(scenario.carriages):
        low, high = travel[i]
        slack = _SLACK * max(1.0, high - low, abs(low), abs(high))
        if not low - slack <= q[i] <= high + slack:
            what = "the [sequence]'s start and targets" if scenario.sequence is not None else "its profile's range"
            raise ParameterError(f"{key}.{carriage.name}: {q[i]:.6g} m is beyond the carriage's travel, "
                                 f"{low:.6g} to {high:.6g} m ({what})")
