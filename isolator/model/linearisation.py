"""The exact model's first-order expansion about a rest pose (exact Jacobians of the one residual)."""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from isolator.model.parameters import ParameterLayout
from isolator.model.residual import newton_euler_residual
from isolator.model.rotations import cardan_matrix

__all__ = ["build_linearisation"]


@lru_cache(maxsize=32)
def build_linearisation(layout: ParameterLayout) -> ca.Function:
    """The exact model's first-order expansion about a rest pose, as a casadi function.

    Coordinates: ``d`` = (mass-centre displacement [m], small rotation vector
    [rad] with ``R = (I + [phi]x) R0``), both world axes. The Jacobians of the one
    :func:`newton_euler_residual` (world components) give

    ``M d'' + C d' + K d + G0 g + G1 g' + Bw w + Ba f = 0``

    for floor motion ``g`` (6: translations, rotations about the world origin),
    a wrench ``w`` at the mass centre (force, moment; world axes) and actuator
    forces ``f``.

    Returns
    -------
    casadi.Function
        ``(z0, c, p) -> (M, C, K, G0, G1, Bw, Ba)`` with ``z0`` the rest pose
        (position [m], Cardan angles [rad]) and ``c`` the carriages' inputs
        (q, q', q'').
    """
    n = layout.n_carriages
    p = ca.SX.sym("p", layout.size)
    c = ca.SX.sym("c", 3 * n)
    z0 = ca.SX.sym("z0", 6)
    d, v, a = ca.SX.sym("d", 6), ca.SX.sym("v", 6), ca.SX.sym("a", 6)
    g = ca.SX.sym("g", 12)
    w = ca.SX.sym("w", 6)
    f = ca.SX.sym("f", layout.n_actuators)
    prm = layout.unpack(p)
    rot = cardan_matrix(d[3:]) @ cardan_matrix(z0[3:])
    body = newton_euler_residual(
        z0[:3] + d[:3], rot, v[:3], rot.T @ v[3:], rot.T @ a[:3], rot.T @ a[3:], c, prm, layout.parents,
        ground=g, actuator_forces=f if layout.n_actuators else None, wrench=w,
    )
    res = ca.vertcat(rot @ body[:3], rot @ body[3:])
    deviations = ca.vertcat(d, v, a, g, w, f)  # all zero at the rest pose

    def jac(var: ca.SX) -> ca.SX:
        return ca.substitute(ca.jacobian(res, var), deviations, ca.SX.zeros(deviations.shape))

    gj = jac(g)
    outs = [jac(a), jac(v), jac(d), gj[:, :6], gj[:, 6:], jac(w), jac(f)]
    return ca.Function(
        "linearise", [z0, c, p], outs, ["z0", "c", "p"], ["M", "C", "K", "G0", "G1", "Bw", "Ba"]
    )
