"""The exact model's first-order expansion about a rest pose (exact Jacobians of the one residual)."""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from isolator.model.elements.base import AttachmentMotion
from isolator.model.elements.pneumatic import PNEUMATIC
from isolator.model.flexible_equations import elastic_state
from isolator.model.parameters import ParameterLayout, PneumaticStructure
from isolator.model.pneumatic_statics import element_of, rest_element_states
from isolator.model.residual import attachment_motion, newton_euler_residual
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

    A top that bends (``layout.flexible``) adds its modal coordinates to ``d``
    (after the six rigid ones) and their rest values to ``z0`` (last); the
    modes' equations follow the six rows.

    For pneumatic tables ``z0`` also holds the groups' rest gauge pressures
    and the chamber pressure deviations ``e`` [Pa] are states too (valves
    closed, as at rest inside their dead zone):

    ``M d'' + C d' + K d + Kp e + ... = 0``, ``e' = Pd d + Pv d' + Pp e + Pg g + Pgd g'``;

    ``Kair`` is the stiffness the air adds when it is slowly squeezed (each
    group's chambers at one pressure, its air kept): ``K + Kair`` is the
    table's static stiffness, which the tipping check uses.

    Returns
    -------
    casadi.Function
        ``(z0, c, p) -> (M, C, K, G0, G1, Bw, Ba)`` with ``z0`` the rest pose
        (position [m], Cardan angles [rad]) and ``c`` the carriages' inputs
        (q, q', q''); pneumatic tables add ``(Kp, Pd, Pv, Pp, Pg, Pgd, Kair)``.
    """
    n = layout.n_carriages
    p = ca.SX.sym("p", layout.size)
    c = ca.SX.sym("c", 3 * n)
    structure = layout.pneumatic
    flexible = layout.flexible
    nm = flexible.n_modes if flexible is not None else 0
    z0 = ca.SX.sym("z0", 6 + (len(structure.groups) if structure is not None else 0) + nm)
    d, v, a = ca.SX.sym("d", 6 + nm), ca.SX.sym("v", 6 + nm), ca.SX.sym("a", 6 + nm)
    g = ca.SX.sym("g", 12)
    w = ca.SX.sym("w", 6)
    f = ca.SX.sym("f", layout.n_actuators)
    prm = layout.unpack(p)
    element = element_of(layout)
    e = ca.SX.sym("e", element.n_states(structure))
    states = rest_element_states(layout, prm, z0[6:]) + e if structure is not None else None
    rot = cardan_matrix(d[3:6]) @ cardan_matrix(z0[3:6])
    pos, w_body = z0[:3] + d[:3], rot.T @ v[3:6]
    elastic = None
    if flexible is not None:
        elastic = elastic_state(flexible, layout.parents, c, prm, z0[z0.shape[0] - nm:] + d[6:], v[6:], a[6:],
                                rot.T @ a[:3], rot.T @ a[3:6], w_body, rot)
    body = newton_euler_residual(
        pos, rot, v[:3], w_body, rot.T @ a[:3], rot.T @ a[3:6], c, prm, layout.parents,
        ground=g, actuator_forces=f if layout.n_actuators else None, wrench=w,
        element=element, element_states=states, elastic=elastic,
    )
    res = ca.vertcat(rot @ body[:3], rot @ body[3:6], body[6:])
    deviations = ca.vertcat(d, v, a, g, w, f, e)  # all zero at the rest pose

    def jac(expr: ca.SX, var: ca.SX) -> ca.SX:
        return ca.substitute(ca.jacobian(expr, var), deviations, ca.SX.zeros(deviations.shape))

    gj = jac(res, g)
    outs = [jac(res, a), jac(res, v), jac(res, d), gj[:, :6], gj[:, 6:], jac(res, w), jac(res, f)]
    names = ["M", "C", "K", "G0", "G1", "Bw", "Ba"]
    if structure is not None and states is not None:
        motion = attachment_motion(pos, rot, v[:3], w_body, prm, g)
        rates = PNEUMATIC.rates(prm, motion, states, structure, valves=False)
        pg = jac(rates, g)
        kp = jac(res, e)
        outs += [kp, jac(rates, d), jac(rates, v), jac(rates, e), pg[:, :6], pg[:, 6:],
                 kp @ ca.substitute(quasi_static_pressures(structure, prm, motion, states, d), deviations,
                                    ca.SX.zeros(deviations.shape))]
        names += ["Kp", "Pd", "Pv", "Pp", "Pg", "Pgd", "Kair"]
    return ca.Function("linearise", [z0, c, p], outs, ["z0", "c", "p"], names)


def quasi_static_pressures(
    structure: PneumaticStructure, prm: dict[str, ca.SX], motion: AttachmentMotion, states: ca.SX, d: ca.SX
) -> ca.SX:
    """``d(pressures)/dd`` when the table is displaced slowly: each group's chambers at one pressure with
    its air kept, ``V dp + n p dV = 0`` summed over the group (rest values, deviations zero)."""
    m = len(structure.chambers)
    damped = structure.damping_slots
    n = prm["air.polytropic"]
    rows: list[ca.SX] = [ca.SX.zeros(1, 6)] * (m + len(damped))
    for members in structure.groups:
        volume = sum((prm["volume"][k] + (prm["damping_volume"][k] if k in damped else 0) for k in members),
                     ca.SX(0))
        change = sum((prm["area"][k] * ca.jacobian(motion.stretch[k][2], d) for k in members), ca.SX.zeros(1, 6))
        row = -n * states[members[0]] * change / volume
        for k in members:
            rows[k] = row
            if k in damped:
                rows[m + damped[k]] = row
    return ca.vertcat(*rows)
