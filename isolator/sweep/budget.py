"""Error-budget columns of a sweep: per design the passive budget's displacement RMS at named points and axes
(:func:`isolator.analysis.budget.error_budget` of the design's table parked with its carriages at their start,
the default band), so that a Pareto front of random error against settling or throughput is one sweep."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from isolator.analysis.budget import AXES, budget_point_names, error_budget, has_random_sources
from isolator.analysis.linear import LinearModel
from isolator.errors import IsolatorError, ParameterError, ScenarioError
from isolator.scenario.definitions import Scenario

__all__ = ["budget_columns", "budget_requests", "budget_values"]


def budget_requests(scenario: Scenario, budget: Sequence[str] | str | None) -> tuple[tuple[str, str], ...]:
    """``budget`` (``"point:axis"`` entries, or one string of them separated by commas) checked against the
    scenario, as (point, axis) pairs in the order given.

    Raises
    ------
    ParameterError
        An entry that is not ``point:axis``, an unknown point or axis, an entry given twice.
    ScenarioError
        The scenario has no random source for a passive budget.
    """
    if budget is None:
        return ()
    entries = budget.split(",") if isinstance(budget, str) else list(budget)
    if not entries:
        return ()
    points = budget_point_names(scenario)
    out: list[tuple[str, str]] = []
    for entry in entries:
        if not isinstance(entry, str):
            raise ParameterError(f"budget: each entry must be 'point:axis', got {entry!r}")
        point, colon, axis = entry.strip().rpartition(":")
        if not colon or not point:
            raise ParameterError(f"budget: expected POINT:AXIS (e.g. '{points[0]}:z'), got {entry.strip()!r}")
        if point not in points:
            raise ParameterError(f"budget: no point named {point!r} (have: {', '.join(points)}"
                                 + ("; a scenario without [[points]] has its mass centre, 'table'"
                                    if not scenario.points else "") + ")")
        if axis not in AXES:
            raise ParameterError(f"budget: the axis of {entry.strip()!r} must be x, y or z, got {axis!r}")
        if (point, axis) in out:
            raise ParameterError(f"budget: {point}:{axis} is asked for twice")
        out.append((point, axis))
    if not has_random_sources(scenario):
        raise ScenarioError("budget: the scenario has no random source for a budget: add [ground.spectrum] (a "
                            "floor spectrum or vc = \"VC-C\"), [[disturbances]] or an actuator's noise_psd")
    return tuple(out)


def budget_columns(requests: Sequence[tuple[str, str]]) -> list[str]:
    """The columns ``budget:<point>:<axis>`` [m] of the requests."""
    return [f"budget:{point}:{axis}" for point, axis in requests]


def budget_values(lin: LinearModel, requests: Sequence[tuple[str, str]]) -> list[float]:
    """The passive budget's displacement RMS [m] of the parked table ``lin`` at each (point, axis), default
    band; NaN for all when the budget fails (a design the budget refuses)."""
    if not requests:
        return []
    points = list(dict.fromkeys(point for point, _ in requests))
    try:
        budget = error_budget(lin, points=points)
    except IsolatorError:
        return [float(np.nan)] * len(requests)
    return [budget.value(point, axis) for point, axis in requests]
