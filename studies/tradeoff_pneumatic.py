"""What the trade-off study's two scales mean for air springs: the sweep's columns and the report's note.

A pneumatic table with valves re-levels for seconds after the stop; the 5 %
settling about the final, level table then measures the valves, not the
isolators. The study's settling figure is the motion's settling about the
slowly leveling table (the sweep's ``dynamic_settling_time_max``,
:attr:`isolator.Response.dynamic_settling_time_max`).
"""

from __future__ import annotations

import numpy as np

from isolator import ParameterError, Scenario
from isolator.model.parameters import ParameterLayout
from isolator.sweep import resolve

__all__ = ["pneumatic_note", "pneumatic_scales"]


def pneumatic_scales(layout: ParameterLayout, stiffness: np.ndarray, damping: np.ndarray) -> dict[str, np.ndarray]:
    """The sweep's ``scale`` columns [-] of designs with every air spring's stiffness scaled by ``stiffness``
    and its damping by ``damping`` (arrays, one per design): both chambers' volumes divided by the stiffness
    scale, the orifice diameter scaled by ``(stiffness damping) ** -0.25`` (its conductance ``G ~ d^4`` by
    ``stiffness damping``, so the series dashpot scales by ``damping``), the horizontal springs and dampers as a
    spring-damper's (:func:`isolator.simulation.scaling.scaled_parameter_sets`). Names no isolator has are left
    out."""
    k, c = np.asarray(stiffness, dtype=float), np.asarray(damping, dtype=float)
    wanted = {"isolators[*].volume": 1.0 / k, "isolators[*].damping_volume": 1.0 / k,
              "isolators[*].orifice.diameter": (k * c) ** -0.25, "isolators[*].horizontal_stiffness": k,
              "isolators[*].horizontal_damping": c}
    out = {}
    for name, values in wanted.items():
        try:
            resolve(layout, name, "scale")
        except ParameterError:
            continue
        out[name] = values
    return out


def pneumatic_note(scenario: Scenario) -> list[str]:
    """The report's lines on what the scales mean for air springs (none for spring-dampers)."""
    return [] if not scenario.is_pneumatic else ["", "Pneumatic isolators: the stiffness scale divides both "
            "chambers' volumes, the damping scale the orifice's conductance (the series dashpot); settling is "
            "that of the motion about the slowly leveling table (the valves' re-leveling left out)."]
