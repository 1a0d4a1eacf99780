"""Piecewise integration for the multibody check: DOP853 restarted at the breakpoints."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence

import numpy as np
from scipy.integrate import solve_ivp

from isolator.errors import IsolatorError

__all__ = ["solve_piecewise"]


def solve_piecewise(
    rhs: Callable[[float, np.ndarray, float], np.ndarray],
    y0: np.ndarray,
    t_eval: np.ndarray,
    breakpoints: Sequence[float],
    rtol: float,
    atol: float | np.ndarray,
    max_step: float = np.inf,
) -> np.ndarray:
    """Integrate with DOP853, restarting at every breakpoint, states at ``t_eval``.

    Parameters
    ----------
    rhs : callable
        ``rhs(t, y, piece_time)``; ``piece_time`` is the middle of the current
        segment, for one-sided profile evaluation.
    y0 : ndarray
        State at ``t_eval[0]``.
    t_eval : ndarray
        Increasing output times [s].
    breakpoints : sequence of float
        Times [s] where the right-hand side may jump.
    rtol, atol : float or ndarray
        DOP853 tolerances (``atol`` per state, in the states' units).
    max_step : float
        Longest step [s].

    Returns
    -------
    ndarray (len(t_eval), len(y0))
    """
    cuts = [float(t_eval[0]), *[b for b in breakpoints if t_eval[0] < b < t_eval[-1]], float(t_eval[-1])]
    states = np.empty((t_eval.size, np.size(y0)))
    filled = np.zeros(t_eval.size, bool)
    y = np.asarray(y0, dtype=float)
    for a, b in itertools.pairwise(cuts):
        if b - a <= 0:
            continue
        mask = (t_eval >= a) & (t_eval <= b) & ~filled
        times = np.union1d(t_eval[mask], [b])
        sol = solve_ivp(rhs, (a, b), y, method="DOP853", t_eval=times, rtol=rtol, atol=atol,
                        max_step=max_step, args=(0.5 * (a + b),))
        if not sol.success:
            raise IsolatorError(f"integration failed between {a:g} s and {b:g} s ({sol.message})")
        states[mask] = sol.y.T[np.isin(times, t_eval[mask])]
        filled |= mask
        y = sol.y[:, -1]
    return states
