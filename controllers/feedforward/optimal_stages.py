"""The optimal feedforward's model along the path: per-stage data and one knot interval's RK4 step.

The state is the table's deviation from its quasi-static path, ``d`` and
``d'`` (12), then (pneumatic tables) the chamber pressures' deviation ``e``
from the path's quasi-static pressures [Pa], then the lagged actuators'
forces:

``M d'' + C d' + K d + Kp e = B f - w``,  ``e' = Pd d + Pv d' + Pp e + r``

with ``r = Pv z_qs' - p_qs'`` the known pressure rate that moving along the
path leaves (:class:`controllers.feedforward.path.AirDemand`).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from isolator.analysis.linear import LinearModel
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario

from .path import QuasiStaticPath, path_demand

__all__ = ["interval_function", "stage_data"]


def stage_data(scenario: Scenario, lin: LinearModel, path: QuasiStaticPath, knots: np.ndarray,
               air: bool = True) -> np.ndarray:
    """Per interval and RK4 stage (start, middle, end): ``M^-1 K``, ``M^-1 C``, ``M^-1 B``, ``M^-1 w``;
    pneumatic tables (unless not ``air``) then ``M^-1 Kp``, ``Pd``, ``Pv``, ``Pp``, ``r``."""
    h = np.diff(knots)
    t = np.column_stack([knots[:-1], knots[:-1] + h / 2, knots[1:]]).ravel()
    sides = np.repeat(knots[:-1] + h / 2, 3)
    demand = path_demand(scenario, lin, path, t, sides)
    inv_m = np.linalg.inv(demand.mass)
    blocks = [inv_m @ demand.stiffness, inv_m @ demand.damping, inv_m @ demand.allocation,
              (inv_m @ demand.wrench[:, :, None])[..., 0]]
    if air and demand.air is not None:
        a = demand.air
        blocks += [inv_m @ a.kp, a.pd, a.pv, a.pp, a.rate[:, :, None]]
    n = h.size
    flat = np.hstack([b.reshape(t.size, -1, order="F") for b in blocks])  # column-major per stage
    return flat.reshape(n, 3 * flat.shape[1])


def interval_function(n_a: int, tau: np.ndarray, lagged: list[int], n_air: int = 0) -> ca.Function:
    """One knot interval: RK4 on the deviation with the exact lag of a linear command."""
    e = ca.SX.sym("e", 12 + n_air)
    fl = ca.SX.sym("f", len(lagged))
    u0, u1 = ca.SX.sym("u0", n_a), ca.SX.sym("u1", n_a)
    h = ca.SX.sym("h")
    base = 36 + 36 + 6 * n_a + 6
    width = base + (18 * n_air + n_air * n_air + n_air if n_air else 0)
    data = ca.SX.sym("d", 3 * width)
    slope = (u1 - u0) / h

    def applied(s: ca.SX | float) -> ca.SX:
        f = u0 + slope * s
        if not lagged:
            return f
        parts = [f[k] for k in range(n_a)]
        for j, k in enumerate(lagged):
            parts[k] = u0[k] + slope[k] * s + (fl[j] - u0[k] + slope[k] * tau[j]) * ca.exp(-s / tau[j]) \
                - slope[k] * tau[j]
        return ca.vertcat(*parts)

    def rates(x: ca.SX, stage: int, s: ca.SX | float) -> ca.SX:
        d = data[stage * width:(stage + 1) * width]
        mk = ca.reshape(d[0:36], 6, 6)
        mc = ca.reshape(d[36:72], 6, 6)
        mb = ca.reshape(d[72:72 + 6 * n_a], 6, n_a)
        mw = d[72 + 6 * n_a:base]
        acc = mb @ applied(s) - mw - mc @ x[6:12] - mk @ x[:6]
        if not n_air:
            return ca.vertcat(x[6:12], acc)
        at = [int(v) for v in np.cumsum([base, 6 * n_air, 6 * n_air, 6 * n_air, n_air * n_air, n_air])]
        mkp = ca.reshape(d[at[0]:at[1]], 6, n_air)
        pd = ca.reshape(d[at[1]:at[2]], n_air, 6)
        pv = ca.reshape(d[at[2]:at[3]], n_air, 6)
        pp = ca.reshape(d[at[3]:at[4]], n_air, n_air)
        air = x[12:]
        return ca.vertcat(x[6:12], acc - mkp @ air, pd @ x[:6] + pv @ x[6:12] + pp @ air + d[at[4]:at[5]])

    k1 = rates(e, 0, 0)
    k2 = rates(e + h / 2 * k1, 1, h / 2)
    k3 = rates(e + h / 2 * k2, 1, h / 2)
    k4 = rates(e + h * k3, 2, h)
    e_next = e + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    f_next = applied(h)[lagged] if lagged else ca.SX.zeros(0, 1)
    return ca.Function("interval", [e, fl, u0, u1, h, data], [e_next, f_next])


check_public(globals())
