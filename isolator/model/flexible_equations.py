"""The exact model of a table whose top bends: its state, rate, static residual, rest state and staged form.

State: the rigid table's 13 (position, quaternion, velocity, body rate), then the modal coordinates
``eta`` and their rates (``docs/scenario-format.md``, "A top that bends"). The static unknowns are the pose
(position, Cardan angles) and ``eta`` at rest: the top's static deflection under the isolators' reactions,
the carriages' weights and any steady force. Every term comes from the one residual
(:func:`isolator.model.residual.newton_euler_residual` with an :class:`ElasticState`). The model has no
staged form: the whole right-hand side is stepped (its time-only part, the carriages' elastic terms, would be
larger than the state); :mod:`isolator.model.quasi_static_top` is the same model with the modes
quasi-static, which has one.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from isolator.model.flexible.coupling import ElasticState, carriage_shapes, carriage_terms, solve_mass
from isolator.model.flexible.structure import ElasticStructure
from isolator.model.residual import carriage_paths, newton_euler_residual
from isolator.model.rotations import cardan_matrix, cardan_to_quaternion, quaternion_rate, quaternion_to_matrix

__all__ = ["FlexibleEquations", "elastic_state", "flexible_equations", "flexible_static"]

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


def elastic_state(structure: ElasticStructure, parents: tuple[int, ...], c: ca.SX, prm: dict[str, ca.SX],
                  eta: ca.SX, rate: ca.SX, accel: ca.SX, acc_body: ca.SX, alpha_body: ca.SX, w_body: ca.SX,
                  rot: ca.SX, shapes: dict[int, tuple[ca.SX, ca.SX, ca.SX]] | None = None) -> ElasticState:
    """The elastic coordinates of a residual with the carriages' terms (:func:`carriage_terms`) for the carriages'
    inputs ``c`` (q, q', q''), the table's orientation ``rot`` and its motion (table frame); ``shapes``: the
    carriages' :func:`carriage_shapes` when already built."""
    n = len(parents)
    g_world = ca.vertcat(0, 0, -prm["gravity"])
    shapes = carriage_shapes(structure, c, n) if shapes is None else shapes
    terms = carriage_terms(structure, carriage_paths(c[: 3 * n], prm, parents), prm["masses"], shapes, eta, rate,
                           accel, acc_body, alpha_body, w_body, rot.T @ g_world, g_world)
    return ElasticState(structure, eta, rate, accel, terms)


def _state(x: ca.SX, nm: int) -> tuple[ca.SX, ...]:
    return x[0:3], x[3:7], x[7:10], x[10:13], x[13:13 + nm], x[13 + nm:13 + 2 * nm]


def flexible_static(structure: ElasticStructure, parents: tuple[int, ...], prm: dict[str, ca.SX], z: ca.SX,
                    rest: ca.SX, rest_extra: dict[str, ca.SX | None]) -> tuple[ca.SX, ca.SX]:
    """The static residual (the residual at rest in pose ``z[:6]`` with the modes at ``z[6:]``, the carriages
    parked at ``rest``'s positions) and the rest state of ``z`` (the modes at rest, every rate zero)."""
    n, nm = len(parents), structure.n_modes
    rot0 = cardan_matrix(z[3:6])
    zero3, zero_m = ca.SX.zeros(3, 1), ca.SX.zeros(nm, 1)
    static = newton_euler_residual(
        z[:3], rot0, zero3, zero3, zero3, zero3, rest[: 3 * n], prm, parents,
        ground=rest_extra["ground"], actuator_forces=rest_extra["actuator_forces"],
        elastic=elastic_state(structure, parents, rest, prm, z[6:], zero_m, zero_m, zero3, zero3, zero3, rot0))
    pose = ca.vertcat(z[:3], cardan_to_quaternion(z[3:6]), ca.SX.zeros(6, 1), z[6:], zero_m)
    return static, pose


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
    shapes = carriage_shapes(structure, c, n)
    elastic = elastic_state(structure, parents, c, prm, eta, rate, acc[6:], acc[:3], acc[3:6], w, rot, shapes)
    res = newton_euler_residual(pos, rot, vel, w, acc[:3], acc[3:6], c[: 3 * n], prm, parents,
                                ground=extra["ground"], actuator_forces=extra["actuator_forces"], elastic=elastic)
    mass = ca.jacobian(res, acc)
    accel = solve_mass(mass[:6, :6], mass[:6, 6:], shapes, _root_masses(structure, prm["masses"]), nm,
                       -ca.substitute(res, acc, ca.SX.zeros(6 + nm, 1)))
    xdot = ca.vertcat(vel, quaternion_rate(qt, w), rot @ accel[:3], accel[3:6], rate, accel[6:])

    static, pose = flexible_static(structure, parents, prm, z, rest, rest_extra)
    return FlexibleEquations(x, xdot, static, pose)
