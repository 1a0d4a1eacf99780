"""Absolute settling windows at points of the table (``[[windows]]``, ``docs/scenario-format.md``)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from isolator.errors import ScenarioError

__all__ = ["WINDOW_AXES", "Window", "check_windows"]

#: the world axes a window may list
WINDOW_AXES = ("x", "y", "z")


@dataclass(frozen=True)
class Window:
    """An absolute window at a point: after the stop, the point's deviation from its settled position must be
    at most ``translation`` on every listed world axis.

    Attributes
    ----------
    point : str
        A ``[[points]]`` name.
    translation : float
        Half-width on each listed axis [m], > 0.
    axes : tuple of str
        World axes among ``x, y, z`` (default all three).
    """

    point: str
    translation: float
    axes: tuple[str, ...] = WINDOW_AXES

    @property
    def axis_indices(self) -> tuple[int, ...]:
        """The listed axes as indices 0, 1, 2."""
        return tuple(WINDOW_AXES.index(a) for a in self.axes)


def check_windows(windows: Sequence[Window], point_names: Sequence[str]) -> None:
    """Each window names a known point, a finite positive translation and known, distinct axes; else one
    :class:`ScenarioError` naming the key (``windows[0].point``)."""
    for i, w in enumerate(windows):
        key = f"windows[{i}]"
        if w.point not in point_names:
            known = ", ".join(point_names) if point_names else "none declared in [[points]]"
            raise ScenarioError(f"{key}.point: unknown point '{w.point}' (points: {known})")
        t = w.translation
        if isinstance(t, bool) or not isinstance(t, int | float) or not math.isfinite(t) or t <= 0:
            raise ScenarioError(f"{key}.translation: must be a finite number > 0 [m], got {t!r}")
        if not w.axes:
            raise ScenarioError(f"{key}.axes: must list at least one of x, y, z")
        for j, a in enumerate(w.axes):
            if a not in WINDOW_AXES:
                raise ScenarioError(f"{key}.axes[{j}]: unknown axis {a!r} (one of x, y, z)")
            if a in w.axes[:j]:
                raise ScenarioError(f"{key}.axes[{j}]: '{a}' is listed twice")
