"""What the trade-off study's two scales mean for air springs: the sweep's columns and the report's note.

A pneumatic table with valves re-levels for seconds after the stop; the 5 %
settling about the final, level table then measures the valves, not the
isolators. The study's settling figure is the motion's settling about the
slowly leveling table (the sweep's ``dynamic_settling_time_max``,
:attr:`isolator.Response.dynamic_settling_time_max`).
"""

from __future__ import annotations

from isolator import Scenario
from isolator.scenario.arguments import check_public

__all__ = ["pneumatic_note"]


def pneumatic_note(scenario: Scenario) -> list[str]:
    """The report's lines on what the scales mean for air springs (none for spring-dampers)."""
    return [] if not scenario.is_pneumatic else ["", "Pneumatic isolators: the stiffness scale divides both "
            "chambers' volumes, the damping scale the orifice's conductance (the series dashpot); settling is "
            "that of the motion about the slowly leveling table (the valves' re-leveling left out)."]


check_public(globals())
