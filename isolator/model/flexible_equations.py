"""The exact model of a table whose top bends: its state, rate, static residual, rest state and staged form.

State: the rigid table's 13 (position, quaternion, velocity, body rate), then the modal coordinates
``eta`` and their rates (``docs/scenario-format.md``, "A top that bends"). The static unknowns are the pose
(position, Cardan angles) and ``eta`` at rest: the top's static deflection under the isolators' reactions,
the carriages' weights and any steady force. Every term comes from the one residual
(:func:`isolator.model.residual.newton_euler_residual` with an :class:`ElasticState`). The model has no
staged form: the whole right-hand side is stepped (its time-only part, the carriages' elastic terms, would be
larger than the state).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from isolator.model.flexible.coupling import ElasticState, carriage_shapes, carriage_terms, solve_mass
from isolator.model.flexible.structure import ElasticStructure
from isolator.model.residual import carriage_paths, newton_euler_residual
from isolator.model.rotations import cardan_matrix, cardan_to_quaternion, quaternion_rate, quaternion_to_matrix

__all__ = ["FlexibleEquations", "flexible_equations"]

@dataclass(frozen=True)
class FlexibleEquations:
    """What :func:`flexible_equations` gives (the fields of a model variant's equations)."""

    x: ca.SX
    xdot: ca.SX
    static: ca.SX
    pose: ca.SX


def _root_masses(structure: ElasticStructure, masses: ca.SX) -> dict[int, ca.SX]:
    out: dict[int, ca.SX] = {}
    for i, shape in enumerate(structure.carriages):
        out[shape.root] = out.get(shape.root, ca.SX(0)) + masses[i]
    return out


def _state(x: ca.SX, nm: int) -> tuple[ca.SX, ...]:
    return x[0:3], x[3:7], x[7:10], x[10:13], x[13:13 + nm], x[13 + nm:13 + 2 * nm]


def flexible_equations(
    structure: ElasticStructure,
    parents: tuple[int, ...],
    c: ca.SX,
    p: ca.SX,
    prm: dict[str, ca.SX],
    z: ca.SX,
    rest: ca.SX,
    extra: dict[str, ca.SX | None],
    rest_extra: dict[str, ca.SX | None],
) -> FlexibleEquations:
    """The exact equations with the top's elastic modes (spring-damper isolators).

    Parameters
    ----------
    structure : ElasticStructure
    parents : tuple of int
        The carriage chain.
    c, p : SX
        The model's inputs and parameters; ``prm`` unpacked.
    z : SX (6 + modes,)
        Static unknowns: position [m], Cardan angles [rad], modal coordinates at rest.
    rest : SX
        The inputs at rest (carriages parked at ``c``'s positions).
    extra, rest_extra : dict
        The floor's motion and the actuator forces within ``c`` and ``rest``.
    """
    n, nm = len(parents), structure.n_modes
    x = ca.SX.sym("x", 13 + 2 * nm)
    pos, qt, vel, w, eta, rate = _state(x, nm)
    rot = quaternion_to_matrix(qt)
    acc = ca.SX.sym("a", 6 + nm)
    g_world = ca.vertcat(0, 0, -prm["gravity"])
    shapes = carriage_shapes(structure, c, n)
    paths = carriage_paths(c[: 3 * n], prm, parents)

    def terms(eta_: ca.SX, rate_: ca.SX, acc_: ca.SX, w_: ca.SX, g_body: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
        return carriage_terms(structure, paths, prm["masses"], shapes, eta_, rate_, acc_[6:], acc_[:3], acc_[3:6],
                              w_, g_body, g_world)

    elastic = ElasticState(structure, eta, rate, acc[6:], terms(eta, rate, acc, w, rot.T @ g_world))
    res = newton_euler_residual(pos, rot, vel, w, acc[:3], acc[3:6], c[: 3 * n], prm, parents,
                                ground=extra["ground"], actuator_forces=extra["actuator_forces"], elastic=elastic)
    mass = ca.jacobian(res, acc)
    accel = solve_mass(mass[:6, :6], mass[:6, 6:], shapes, _root_masses(structure, prm["masses"]), nm,
                       -ca.substitute(res, acc, ca.SX.zeros(6 + nm, 1)))
    xdot = ca.vertcat(vel, quaternion_rate(qt, w), rot @ accel[:3], accel[3:6], rate, accel[6:])

    # the static residual: the same residual at rest in pose z[:6] with the modes at z[6:]
    rest_paths = carriage_paths(rest[: 3 * n], prm, parents)
    rest_shapes = carriage_shapes(structure, rest, n)
    rot0 = cardan_matrix(z[3:6])
    zero3, zero_m = ca.SX.zeros(3, 1), ca.SX.zeros(nm, 1)
    rest_terms = carriage_terms(structure, rest_paths, prm["masses"], rest_shapes, z[6:], zero_m, zero_m, zero3,
                                zero3, zero3, rot0.T @ g_world, g_world)
    static = newton_euler_residual(
        z[:3], rot0, zero3, zero3, zero3, zero3, rest[: 3 * n], prm, parents,
        ground=rest_extra["ground"], actuator_forces=rest_extra["actuator_forces"],
        elastic=ElasticState(structure, z[6:], zero_m, zero_m, rest_terms))
    pose = ca.vertcat(z[:3], cardan_to_quaternion(z[3:6]), ca.SX.zeros(6, 1), z[6:], zero_m)
    return FlexibleEquations(x, xdot, static, pose)
