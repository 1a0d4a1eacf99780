"""The trade-off study's transient runs for pneumatic tables: settling about the leveling table.

A pneumatic table with valves re-levels for seconds after the stop; the 5 %
settling about the final, level table then measures the valves, not the
isolators. Here each design is one run, and its settling is the motion's
settling about the slowly leveling table
(:attr:`isolator.Response.dynamic_settling_time_max`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from isolator import Band, IsolatorError, Scenario, Simulator

__all__ = ["pneumatic_note", "pneumatic_settling"]


def pneumatic_settling(
    sim: Simulator, stiffness: np.ndarray, damping: np.ndarray, say: Callable[[str], None], band: Band | None = None
) -> tuple[np.ndarray, dict[int, str], np.ndarray]:
    """Settling about the leveling table [s] per design (NaN where a run cannot show it), why runs failed, and
    each design's band's six half-widths [m, rad] (NaN: no run).

    Parameters
    ----------
    sim : Simulator
    stiffness, damping : ndarray (runs,)
        Scales on every isolator's springs and dampers
        (:func:`isolator.simulation.scaling.scaled_parameter_sets`).
    say : callable
        Progress lines.
    band : Band, optional
        The settling band (default: the scenario's rule).
    """
    out = np.full(stiffness.size, np.nan)
    widths = np.full((stiffness.size, 6), np.nan)
    failures: dict[int, str] = {}
    params = sim.scaled_parameter_sets(stiffness, damping)
    step = max(1, stiffness.size // 10)
    for r, p in enumerate(params):
        try:
            run = sim.run(p=p, band=band)
        except IsolatorError as exc:
            failures[r] = str(exc)
            continue
        value = run.dynamic_settling_time_max
        out[r] = np.nan if value is None else value
        widths[r] = run.band.half_widths
        if (r + 1) % step == 0 or r + 1 == stiffness.size:
            say(f"  runs: {r + 1}/{stiffness.size}")
    return out, failures, widths


def pneumatic_note(scenario: Scenario) -> list[str]:
    """The report's lines on what the scales mean for air springs (none for spring-dampers)."""
    return [] if not scenario.is_pneumatic else ["", "Pneumatic isolators: the stiffness scale divides both "
            "chambers' volumes, the damping scale the orifice's conductance (the series dashpot); settling is "
            "that of the motion about the slowly leveling table (the valves' re-leveling left out)."]
