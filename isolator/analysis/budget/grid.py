"""The frequency grid of an error budget: points where the resonances and the sources' corners are, refined
until the integral of every output's power spectral density is converged.

A fixed logarithmic grid misses a lightly damped mode (its half-power width is ``2 zeta f``: 0.05 Hz for a
5 Hz mode at 0.5 % damping). The grid here starts from a logarithmic grid, adds points across each pole's
half-power band and on both sides of every corner of the sources' densities (a third-octave band's edge is a
jump), then halves every interval whose trapezoid and Simpson estimates differ by more than a share of the
tolerance, until none does.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

__all__ = ["integrate_psd", "seed_grid"]

#: points per decade of the starting grid
_PER_DECADE = 60
#: points across a pole's band (+-10 half-power widths)
_ACROSS_POLE = 41
#: relative side of a jump's two points
_JUMP = 1e-9


def seed_grid(band: tuple[float, float], poles: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """The starting grid [Hz] in ``band``: logarithmic, dense across each pole of ``poles`` [1/s] below 50 %
    damping, and on both sides of each corner [Hz]."""
    lo, hi = band
    decades = max(math.log10(hi / lo), 1e-3)
    parts = [np.geomspace(lo, hi, max(math.ceil(decades * _PER_DECADE) + 1, 3))]
    poles = np.asarray(poles, dtype=complex)
    wn = np.abs(poles)
    with np.errstate(invalid="ignore", divide="ignore"):
        zeta = np.where(wn > 0, -poles.real / np.where(wn > 0, wn, 1.0), 1.0)
    u = np.linspace(-10.0, 10.0, _ACROSS_POLE)
    for w, z in zip(wn, zeta, strict=True):
        fn = w / (2 * math.pi)
        if z < 0.5 and lo / 10 < fn < hi * 10:
            width = max(z, 1e-6) * fn
            parts.append(fn + u * width)
            parts.append(fn * np.geomspace(0.5, 2.0, 25))
    c = np.asarray(corners, dtype=float)
    parts += [c * (1 - _JUMP), c * (1 + _JUMP)]
    f = np.concatenate(parts)
    return np.unique(f[(f >= lo) & (f <= hi)])


def integrate_psd(evaluate: Callable[[np.ndarray], np.ndarray], grid: np.ndarray, tol: float = 2e-4,
                  max_rounds: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Refine ``grid`` until the trapezoid integral of every output's density is converged.

    Parameters
    ----------
    evaluate : callable
        Frequencies [Hz] (n,) -> densities (n, outputs, sources) [SI^2/Hz], each >= 0.
    grid : ndarray
        The starting grid [Hz], increasing.
    tol : float
        Relative error allowed on each output's integral (summed over the sources), shared by the
        intervals: an interval is halved while its trapezoid and Simpson estimates differ by more than
        ``tol / intervals`` of the output's integral.
    max_rounds : int
        Halvings at most.

    Returns
    -------
    frequency : ndarray (n,)
        [Hz], increasing.
    density : ndarray (n, outputs, sources)
        At those frequencies.
    """
    f = np.asarray(grid, dtype=float)
    values = evaluate(f)
    active = np.ones(f.size - 1, dtype=bool)
    for _ in range(max_rounds):
        if not active.any():
            break
        a, b = f[:-1][active], f[1:][active]
        mid = 0.5 * (a + b)
        fresh = evaluate(mid)
        total = values.sum(axis=2)
        integral = np.trapezoid(total, f, axis=0)  # (outputs,)
        scale = np.maximum(integral, 1e-9 * max(float(integral.max(initial=0.0)), 1e-300))
        ya, yb, ym = total[:-1][active], total[1:][active], fresh.sum(axis=2)
        width = (b - a)[:, None]
        simpson = width / 6 * (ya + 4 * ym + yb)
        trapezoid = width / 2 * (ya + yb)
        error = np.max(np.abs(simpson - trapezoid) / scale[None, :], axis=1)
        failing = error > tol / active.sum()
        order = np.argsort(np.concatenate([f, mid]), kind="stable")
        new_f = np.concatenate([f, mid])[order]
        values = np.concatenate([values, fresh])[order]
        # each old interval becomes two; the halves of a failing one stay active
        nxt = np.zeros(new_f.size - 1, dtype=bool)
        position = np.searchsorted(new_f, mid)
        nxt[position[failing] - 1] = True
        nxt[position[failing]] = True
        f, active = new_f, nxt
    return f, values
