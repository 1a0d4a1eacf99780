"""Absolute settling windows at points of the table (``[[windows]]``, ``docs/scenario-format.md``)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

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
    random : float or None
        ``K`` (> 0): the window is narrowed on each listed axis by ``K`` times the point's budgeted random
        displacement RMS there (``[[windows]] random``), so that the transient leaves room for it.
    margin : tuple of float
        The narrowing ``K sigma`` [m] per listed axis, once the budget has been taken
        (:func:`isolator.simulation.window_random.with_random_margins`); empty before, and without ``random``.
    """

    point: str
    translation: float
    axes: tuple[str, ...] = WINDOW_AXES
    random: float | None = None
    margin: tuple[float, ...] = ()

    @property
    def axis_indices(self) -> tuple[int, ...]:
        """The listed axes as indices 0, 1, 2."""
        return tuple(WINDOW_AXES.index(a) for a in self.axes)

    @property
    def half_widths(self) -> np.ndarray:
        """The half-width [m] on each listed axis that the transient must stay within: ``translation`` less the
        random motion's margin."""
        width = np.full(len(self.axes), float(self.translation))
        return width - np.asarray(self.margin, dtype=float) if self.margin else width

    @property
    def random_margins(self) -> dict[str, float] | None:
        """``{axis: K sigma}`` [m] over the listed axes (the JSON's ``window_random`` entry), None without
        ``random``."""
        if self.random is None or not self.margin:
            return None
        return {a: float(m) for a, m in zip(self.axes, self.margin, strict=True)}


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
        k = w.random
        if k is not None and (isinstance(k, bool) or not isinstance(k, int | float) or not math.isfinite(k) or k <= 0):
            raise ScenarioError(f"{key}.random: must be a finite number > 0 (sigmas of the random motion), got {k!r}")
        if w.margin and (len(w.margin) != len(w.axes) or w.random is None):
            raise ScenarioError(f"{key}.margin: one value per listed axis, and only with random")
