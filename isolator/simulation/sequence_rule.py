"""The step-and-settle rule on sampled deviations (``docs/scenario-format.md``, "Windows at points and
step-and-settle sequences"): from the stop, wait until every window holds continuously for ``measure``
seconds; the settled time is the start of that interval.

The deviations come on a grid of at least 1 kHz read from the integrator's dense output; each crossing of a
window edge is placed by linear interpolation between the two grid times around it (as
:func:`~isolator.simulation.window_settling.window_exit` places the last exit), so the settled time does not
depend on the output sample rate.
"""

from __future__ import annotations

import numpy as np

__all__ = ["held_from", "normalised"]


def normalised(deviations: list[np.ndarray], half_widths: list[float]) -> np.ndarray:
    """Every window's listed-axis deviations (axes, N) [m] divided by its half-width, stacked (rows, N):
    every window holds where every row is within [-1, 1]."""
    rows = [np.atleast_2d(d) / w for d, w in zip(deviations, half_widths, strict=True)]
    return np.vstack(rows) if rows else np.zeros((0, 0))


def _crossing(t0: float, t1: float, d0: np.ndarray, d1: np.ndarray, leaving: bool) -> float:
    """When the rows (d0 at t0, d1 at t1) cross the window edge +-1 by linear interpolation: the first
    row to leave (``leaving``) or the last to come back."""
    if leaving:
        rows = np.abs(d1) > 1.0
        edge = np.copysign(1.0, d1[rows])
        frac = (edge - d0[rows]) / (d1[rows] - d0[rows])
        return float(t0 + (t1 - t0) * np.clip(frac, 0.0, 1.0).min())
    rows = np.abs(d0) > 1.0
    edge = np.copysign(1.0, d0[rows])
    frac = (d0[rows] - edge) / (d0[rows] - d1[rows])
    return float(t0 + (t1 - t0) * np.clip(frac, 0.0, 1.0).max())


def held_from(t: np.ndarray, rows: np.ndarray, measure: float) -> float | None:
    """The start of the first interval of length ``measure`` [s] over which every row stays within
    [-1, 1], or None if the data do not show one yet.

    Parameters
    ----------
    t : ndarray (N,)
        Increasing times [s]; ``t[0]`` is where the wait starts (the stop).
    rows : ndarray (rows, N)
        Deviations divided by their window's half-width (:func:`normalised`).
    measure : float
        [s], >= 0; 0 gives the first time every window holds.

    Returns
    -------
    float or None
        The settled time [s]; None when no interval ends by ``t[-1]`` (longer data needed).
    """
    t = np.asarray(t, dtype=float)
    d = np.asarray(rows, dtype=float).reshape(-1, t.size)
    inside = np.all(np.abs(d) <= 1.0, axis=0)
    if not inside.any():
        return None
    change = np.diff(inside.astype(np.int8))
    starts = np.flatnonzero(change == 1) + 1
    ends = np.flatnonzero(change == -1)  # the last inside index of each run
    if inside[0]:
        starts = np.concatenate([[0], starts])
    if inside[-1]:
        ends = np.concatenate([ends, [t.size - 1]])
    for a, b in zip(starts, ends, strict=True):
        enter = float(t[0]) if a == 0 else _crossing(t[a - 1], t[a], d[:, a - 1], d[:, a], leaving=False)
        if b == t.size - 1:  # still inside when the data end
            return enter if t[-1] - enter >= measure * (1 - 1e-12) else None
        leave = _crossing(t[b], t[b + 1], d[:, b], d[:, b + 1], leaving=True)
        if leave - enter >= measure * (1 - 1e-12) and leave > enter:
            return enter
    return None
