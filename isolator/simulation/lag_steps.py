"""The forces an RK4 step gives its four stages for an actuator's first-order lag ``tau f' = u - f``, so that the
step integrates the lag's exact force as it would a linear table's input, however fast the lag.

For ``x' = A x + B f``, one RK4 step with the stage forces ``b1..b4`` adds ``h/6 (b1 + 2 b2 + 2 b3 + b4) B``,
``h^2/6 (b1 + b2 + b3) A B``, ``h^3/12 (b1 + b2) A^2 B`` and ``h^4/24 b1 A^3 B`` to the state; the exact solution
adds the moments ``int_0^h (h - s)^n / n! f(s) ds A^n B``. :func:`lag_stages` chooses the ``b`` whose four
sums are the lag's exact moments (the command linear between the step's start, middle and end, clipped at the
actuator's limit with its kinks inside the step), so the step is as exact for the lagged force as for the table
itself (through ``h^3 A^3``) and the step rule follows the table's own eigenvalues
(:func:`~isolator.simulation.stepping.fastest_rate`). The forces runs (numpy,
:func:`~isolator.simulation.actuation.with_forces`), the compiled closed loop (casadi,
:mod:`isolator.simulation.sampled_loop`) and the FMU's step (:func:`lag_rows`, generated C) use this one formula.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np

__all__ = ["clipped_stages", "crosses", "held_interval", "lag_rows", "lag_stages", "lag_weights"]

#: below this ``|z|`` the exponential's moments come down from the series of the fifth (16 terms: within 1e-16),
#: above it up from the first (which divides by ``z``)
_SERIES_BELOW = 1.0
_TERMS = 16


def _exponential_moments(z: Any, exp: Any, select: Any) -> tuple[list[Any], list[Any]]:
    """``g_k = int_0^1 th^k e^(z th) dth`` and ``q_k = (g_k - 1/(k+1)) / z = (g_0 - g_(k+1)) / (k+1)``,
    k = 0..3, for ``z <= 0``: each recursion ``z g_k = e^z - k g_(k-1)`` in its stable direction."""
    small = z > -_SERIES_BELOW
    safe = select(small, -1.0, z)  # the upward branch, never at z = 0
    ez, e_small = exp(safe), exp(z)
    term, down = 1.0, 1.0 / 5
    for m in range(1, _TERMS):
        term = term * z / m
        down = down + term / (m + 5)
    downward = [down]
    for k in range(4, 0, -1):
        downward.insert(0, (e_small - z * downward[0]) / k)
    upward = [(ez - 1.0) / safe]
    for k in range(1, 5):
        upward.append((ez - k * upward[-1]) / safe)
    g = [select(small, a, b) for a, b in zip(downward, upward, strict=True)]
    return g[:4], [(g[0] - g[k + 1]) / (k + 1) for k in range(4)]


def _pieces(u0: Any, um: Any, u1: Any, limit: Any, lo: Any, hi: Any, select: Any) -> list[tuple[Any, Any, Any, Any]]:
    """The command over a step as linear pieces ``(start, length, value at start, value at end)`` in units of the
    step: its two halves, each cut where it crosses ``+-limit`` and clipped there (None: not clipped)."""
    if limit is None:
        return [(0.0, 0.5, u0, um), (0.5, 0.5, um, u1)]
    out = []
    for start, ua, ub in ((0.0, u0, um), (0.5, um, u1)):
        slope = ub - ua
        safe = select(slope == 0, 1.0, slope)  # no crossing when 0: its cuts are not used
        cuts = [lo(hi((sign * limit - ua) / safe, 0.0), 1.0) for sign in (1.0, -1.0)]
        marks = [0.0, lo(cuts[0], cuts[1]), hi(cuts[0], cuts[1]), 1.0]
        values = [lo(hi(ua + slope * m, -limit), limit) for m in marks]
        out += [(start + marks[i] / 2, (marks[i + 1] - marks[i]) / 2, values[i], values[i + 1]) for i in range(3)]
    return out


def lag_stages(f0: Any, u0: Any, um: Any, u1: Any, h: Any, tau: Any, limit: Any = None
               ) -> tuple[list[Any], list[Any]]:
    """The forces an RK4 step of length ``h`` gives its four stages for a lagged actuator, and the lag's force at
    the step's middle and end.

    The command [N] is ``u0``, ``um``, ``u1`` at the step's start, middle and end and linear between them,
    clipped at ``+-limit`` (its kinks where it crosses them, inside the step, followed exactly); the lag
    ``tau f' = u - f`` starts from ``f0`` [N]. The stage forces ``b1..b4`` are those whose RK4 step of a linear
    system ``x' = A x + B f`` equals the exact one through ``h^3 A^3``: the moments
    ``int_0^h (h - s)^n / n! f(s) ds``, n = 0..3, of the lag's exact force equal RK4's
    ``h/6 (b1 + 2 b2 + 2 b3 + b4)``, ``h^2/6 (b1 + b2 + b3)``, ``h^3/12 (b1 + b2)``, ``h^4/24 b1`` (a constant
    force gives its value to every stage; a fast lag's transient, its weight in the step).

    Parameters
    ----------
    f0, u0, um, u1 : float, ndarray or casadi expression
        [N], broadcast together.
    h, tau : float, ndarray or casadi expression
        The step and the lag's time constant [s], ``h > 0``, ``tau > 0``.
    limit : float, ndarray or casadi expression, optional
        The actuator's ``max_force`` [N] (None: the command as it is).

    Returns
    -------
    stages : list
        ``[b1, b2, b3, b4]`` [N].
    forces : list
        The lag's exact force at ``h / 2`` and ``h`` [N].
    """
    symbolic = any(isinstance(v, (ca.SX, ca.MX)) for v in (f0, u0, um, u1, h, tau, limit))
    exp, select, lo, hi = (ca.exp, ca.if_else, ca.fmin, ca.fmax) if symbolic else (
        np.exp, np.where, np.minimum, np.maximum)
    moments: list[Any] = [0.0] * 4
    ends, fa = [], f0
    # each piece: the moments of f(a + w) against w^k over its length l, in units of l^(k+1), shifted to
    # (1 - a - w)^n / n! (units of the step)
    shared: dict[float, tuple[Any, tuple[list[Any], list[Any]]]] = {}  # pieces of one length: their moments once
    for start, length, ua, ub in _pieces(u0, um, u1, limit, lo, hi, select):
        if isinstance(length, float) and length in shared:
            z, (g, q) = shared[length]
        else:
            z = -length * h / tau
            g, q = _exponential_moments(z, exp, select)
            if isinstance(length, float):
                shared[length] = z, (g, q)
        mu = [ua / (k + 1) + (ub - ua) / (k + 2) + (fa - ua) * g[k] - (ub - ua) * q[k] for k in range(4)]
        scaled = [length ** (k + 1) * mu[k] for k in range(4)]
        for n in range(4):
            moments[n] = moments[n] + sum(math.comb(n, k) * (1 - start) ** (n - k) * (-1) ** k * scaled[k]
                                          for k in range(n + 1)) / math.factorial(n)
        fa = ub + (fa - ua) * exp(z) - (ub - ua) * g[0]
        ends.append(fa)
    b1 = 24 * moments[3]
    b2 = 12 * moments[2] - b1
    b3 = 6 * moments[1] - b1 - b2
    b4 = 6 * moments[0] - b1 - 2 * b2 - 2 * b3
    return [b1, b2, b3, b4], [ends[len(ends) // 2 - 1], ends[-1]]


def held_interval(lag: np.ndarray, command: np.ndarray, order: np.ndarray, substeps: int, h: float,
                  tau: np.ndarray, limits: np.ndarray, lagged: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One interval of ``substeps`` RK4 steps over ``h`` [s] with a command ``command`` (2 substeps + 1 grid nodes,
    actuators) [N], the actuators' forces from ``lag`` [N] at its start, as the compiled loop takes them (its
    reference in Python, for tests and benchmarks): the forces at the nodes (clipped; lagged where ``lagged``), the
    forces each step's four stages take (``order``: the stages' nodes, by :func:`lag_stages` where lagged) and
    the lags' forces at the end."""
    applied = np.clip(command, -limits, limits)
    taken = applied[order] if lagged.any() else applied
    for j in range(substeps if lagged.any() else 0):
        stages, (half, end) = lag_stages(lag, command[2 * j], command[2 * j + 1], command[2 * j + 2], h / substeps,
                                         tau, limits)
        applied[2 * j, lagged], applied[2 * j + 1, lagged], applied[2 * j + 2, lagged] = \
            lag[lagged], half[lagged], end[lagged]
        for k in range(4):
            taken[4 * j + k, lagged] = stages[k][lagged]
        lag = end
    return applied, taken, lag


def _flat(result: tuple[list[Any], list[Any]]) -> list[Any]:
    """:func:`lag_stages`' stage forces and its middle and end forces, one list."""
    return [*result[0], *result[1]]


def crosses(u0: Any, um: Any, u1: Any, limit: Any) -> Any:
    """Where a half of the step's command (linear from ``u0`` to ``um``, from ``um`` to ``u1``) crosses ``+-limit``
    strictly inside it: a kink of the clipped command inside the step (numpy booleans, or casadi 0/1)."""
    symbolic = any(isinstance(v, (ca.SX, ca.MX)) for v in (u0, um, u1, limit))
    either = ca.logic_or if symbolic else np.logical_or
    out = None
    for a, b in ((u0, um), (um, u1)):
        for edge in (limit, -limit):
            kink = (a - edge) * (b - edge) < 0
            out = kink if out is None else either(out, kink)
    return out


def clipped_stages(u0: np.ndarray, um: np.ndarray, u1: np.ndarray, lengths: np.ndarray, which: np.ndarray,
                   tau: np.ndarray, limit: np.ndarray) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """:func:`lag_stages` of many steps (numpy) as the lag's linearity splits it: from zero force, and per unit of
    the force at the step's start.

    Parameters
    ----------
    u0, um, u1 : ndarray (steps, ..., lags)
        The commands [N] at the steps' starts, middles and ends (unclipped).
    lengths, which : ndarray
        The distinct step lengths [s] and each step's among them (``steps``,).
    tau, limit : ndarray (lags,)
        [s], [N].

    Returns
    -------
    own : list of ndarray
        ``b1..b4``, the middle and end forces from zero force [N]: within the limits, the weights of each
        distinct step applied to the clipped command; the clipping's kinks followed where a step's command
        :func:`crosses` its limit.
    unit : list of ndarray
        The same per newton of force at the start, (steps, 1, ..., lags).
    """
    steps = lengths[(slice(None),) + (None,) * (u0.ndim - 1)]
    units = np.eye(4)
    weights = [_flat(lag_stages(units[c, 0], units[c, 1], units[c, 2], units[c, 3], steps, tau)) for c in range(4)]
    per_step = [[w[which] for w in column] for column in weights]  # (steps, 1.., lags) each
    clipped = [np.clip(u, -limit, limit) for u in (u0, um, u1)]
    own = [sum(per_step[c + 1][k] * clipped[c] for c in range(3)) for k in range(6)]
    cut = crosses(u0, um, u1, limit)
    if cut.any():
        full = np.broadcast_arrays(u0, steps[which], tau, limit)
        exact = _flat(lag_stages(0.0, u0[cut], um[cut], u1[cut], full[1][cut], full[2][cut], full[3][cut]))
        for whole, part in zip(own, exact, strict=True):
            whole[cut] = part
    return own, per_step[0]


def lag_weights(h: ca.SX, taus: Sequence[float]) -> ca.SX:
    """(6 per time constant, 4): for each of ``taus`` [s] the matrix ``W`` of :func:`lag_stages` over a step of
    ``h`` [s] for a command within its limits, ``(b1..b4, f_half, f_end) = W (f0, u0, um, u1)`` (casadi SX)."""
    unit = ca.SX.sym("unit", 4)
    parts = ca.vertsplit(unit)
    return ca.vertcat(*[ca.densify(ca.jacobian(ca.vertcat(*_flat(lag_stages(parts[0], parts[1], parts[2], parts[3], h,
                                                                              t))), unit)) for t in taus])


def lag_rows(f0: ca.SX, u0: ca.SX, um: ca.SX, u1: ca.SX, h: ca.SX, tau: Sequence[float], limit: Sequence[float],
             weights: ca.SX | None = None) -> ca.SX:
    """(lags, 6): :func:`lag_stages` of lags with time constants ``tau`` [s] and limits ``limit`` [N] (columns
    ``b1..b4``, the middle and end forces), casadi SX. Without ``weights``, the clipping's kinks inside the step
    followed (for a step where :func:`crosses` says so); with them (:func:`lag_weights` of the sorted distinct
    ``tau``), the two halves of the clipped command, linear in the forces: the same numbers where no command
    crosses its limit, at a fraction of the cost."""
    n = len(tau)
    if weights is None:
        return ca.vertcat(*[ca.horzcat(*_flat(lag_stages(f0[k], u0[k], um[k], u1[k], h, tau[k], limit[k])))
                            for k in range(n)])
    lim = ca.DM(list(limit))
    clipped = [ca.fmin(ca.fmax(u, -lim), lim) for u in (u0, um, u1)]
    at = {t: 6 * i for i, t in enumerate(sorted(set(tau)))}
    return ca.vertcat(*[(weights[at[tau[k]]:at[tau[k]] + 6, :] @ ca.vertcat(
        f0[k], clipped[0][k], clipped[1][k], clipped[2][k])).T for k in range(n)])
