"""What a design buys in throughput: window settling and moves per hour of a single move.

A machine that repeats the scenario's move and waits after each until every ``[[windows]]`` point holds its
window does one move every ``move time + window settling time`` seconds (the move time from the first
carriage's start to the stop). Scenarios with a ``[sequence]`` have their own figure, the sequence's
throughput (:class:`isolator.SequenceResult`).
"""

from __future__ import annotations

from isolator import Response
from isolator.scenario.arguments import check_public

__all__ = ["window_cycle"]


def window_cycle(response: Response) -> tuple[float | None, float | None]:
    """A run's largest window settling time [s] and moves per hour (:attr:`Response.moves_per_hour`);
    (None, None) without ``[[windows]]``."""
    if response.windows is None:
        return None, None
    return response.window_settling_time_max, response.moves_per_hour


check_public(globals())
