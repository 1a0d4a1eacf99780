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


def normalised(deviations: list[np.ndarray], half_widths: list[float] | list[np.ndarray]) -> np.ndarray:
    """Every window's listed-axis deviations (axes, N) [m] divided by its half-width, stacked (rows, N):
    every window holds where every row is within [-1, 1]."""
    rows = [np.atleast_2d(d) / w for d, w in zip(deviations, half_widths, strict=True)]
    return np.vstack(rows) if rows else np.zeros((0, 0))


def _crossings(t: np.ndarray, d: np.ndarray, k: np.ndarray, leaving: bool) -> np.ndarray:
    """When the rows cross the window edge +-1 between grid times ``k`` and ``k + 1`` (each of ``k``), by
    linear interpolation: the first row to leave (``leaving``, outside at ``k + 1``) or the last one to
    come back (outside at ``k``)."""
    d0, d1 = d[:, k], d[:, k + 1]
    out = np.abs(d1 if leaving else d0) > 1.0
    edge = np.copysign(1.0, d1 if leaving else d0)
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.clip((edge - d0) / (d1 - d0), 0.0, 1.0)
    frac = np.where(out, frac, np.inf if leaving else -np.inf)
    pick = frac.min(axis=0) if leaving else frac.max(axis=0)
    return np.asarray(t[k] + (t[k + 1] - t[k]) * pick)


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
    enter = np.full(starts.size, float(t[0]))
    later = starts > 0
    enter[later] = _crossings(t, d, starts[later] - 1, leaving=False)
    open_end = ends == t.size - 1  # still inside when the data end (the last run only)
    leave = np.full(ends.size, np.inf)
    leave[~open_end] = _crossings(t, d, ends[~open_end], leaving=True)
    closed = ~open_end & (leave - enter >= measure * (1 - 1e-12)) & (leave > enter)
    if closed.any():
        return float(enter[np.argmax(closed)])
    if open_end[-1] and t[-1] - enter[-1] >= measure * (1 - 1e-12):
        return float(enter[-1])
    return None
