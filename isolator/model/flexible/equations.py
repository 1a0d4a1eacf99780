"""The exact model of a table whose top bends: its state, rate, static residual, rest state and staged form.

State: the rigid table's 13 (position, quaternion, velocity, body rate), then the modal coordinates
``eta`` and their rates (``docs/scenario-format.md``, "A top that bends"). The static unknowns are the pose
(position, Cardan angles) and ``eta`` at rest: the top's static deflection under the isolators' reactions,
the carriages' weights and any steady force. Every term comes from the one residual
(:func:`isolator.model.residual.newton_euler_residual` with an :class:`ElasticState`).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from isolator.model.flexible.coupling import ElasticState, carriage_shapes, carriage_terms, inverse_mass
from isolator.model.flexible.structure import ElasticStructure
from isolator.model.residual import carriage_kinematics, carriage_paths, newton_euler_residual
from isolator.model.rotations import cardan_matrix, cardan_to_quaternion, quaternion_rate, quaternion_to_matrix

__all__ = ["FlexibleEquations", "flexible_equations"]

#: the rigid carriage moments the staged form keeps per stage time: (name, packed size)
_MOMENTS = (("S", 3), ("Sd", 3), ("Sdd", 3), ("Jc", 9), ("Hd", 3), ("B", 9))


@dataclass(frozen=True)
class FlexibleEquations:
    """What :func:`flexible_equations` gives (the fields of a model variant's equations)."""

    x: ca.SX
    xdot: ca.SX
    static: ca.SX
    pose: ca.SX
    staged: tuple[ca.Function, ca.Function]


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
    inv = inverse_mass(mass[:6, :6], mass[:6, 6:], shapes, _root_masses(structure, prm["masses"]), nm)
    accel = -inv @ ca.substitute(res, acc, ca.SX.zeros(6 + nm, 1))
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
    staged = _staged(structure, parents, x, c, p, prm, extra, inv, terms)
    return FlexibleEquations(x, xdot, static, pose, staged)


def _staged(structure: ElasticStructure, parents: tuple[int, ...], x: ca.SX, c: ca.SX, p: ca.SX,
            prm: dict[str, ca.SX], extra: dict[str, ca.SX | None], inv: ca.SX, terms: object
            ) -> tuple[ca.Function, ca.Function]:
    """The right-hand side split as :mod:`isolator.model.staging` splits the rigid one: per stage time the
    carriages' rigid moments, the inverse mass matrix and the carriages' elastic terms as the affine map
    ``L y + l0`` of ``y = (eta, eta', omega, g_body)``; per run the rest."""
    n, nm = len(parents), structure.n_modes
    size = 6 + nm
    y = ca.SX.sym("y", 2 * nm + 6)
    zero_acc = ca.SX.zeros(size, 1)
    parts = terms(y[:nm], y[nm:2 * nm], zero_acc, y[2 * nm:2 * nm + 3], y[2 * nm + 3:])  # type: ignore[operator]
    affine = ca.vertcat(*parts)
    lin, offset = ca.jacobian(affine, y), ca.substitute(affine, y, ca.SX.zeros(y.shape))
    kin = carriage_kinematics(c[: 3 * n], prm, parents)
    rest = c[3 * n:]
    time_only = ca.vertcat(*[ca.vec(kin[name]) for name, _ in _MOMENTS], ca.vec(inv), ca.vec(lin), offset, rest)
    staged_inputs = ca.Function("staged_inputs", [c, p], [time_only], ["c", "p"], ["v"])

    v = ca.SX.sym("v", time_only.shape[0])
    at, moments = 0, {"m": ca.sum1(prm["masses"])}
    for name, k in _MOMENTS:
        moments[name] = ca.reshape(v[at:at + k], 3, 3) if k == 9 else v[at:at + k]
        at += k
    inv_v = ca.reshape(v[at:at + size * size], size, size)
    at += size * size
    lin_v = ca.reshape(v[at:at + size * (2 * nm + 6)], size, 2 * nm + 6)
    at += size * (2 * nm + 6)
    offset_v = v[at:at + size]
    at += size
    moved = {k: None if e is None else ca.substitute(e, rest, v[at:]) for k, e in extra.items()}
    pos, qt, vel, w, eta, rate = _state(x, nm)
    rot = quaternion_to_matrix(qt)
    g_body = rot.T @ ca.vertcat(0, 0, -prm["gravity"])
    affine_v = lin_v @ ca.vertcat(eta, rate, w, g_body) + offset_v
    elastic = ElasticState(structure, eta, rate, ca.SX.zeros(nm, 1), (affine_v[:3], affine_v[3:6], affine_v[6:]))
    zero3 = ca.SX.zeros(3, 1)
    bias = newton_euler_residual(pos, rot, vel, w, zero3, zero3, None, prm, parents, kin=moments,
                                 ground=moved["ground"], actuator_forces=moved["actuator_forces"], elastic=elastic)
    accel = -inv_v @ bias
    xdot = ca.vertcat(vel, quaternion_rate(qt, w), rot @ accel[:3], accel[3:6], rate, accel[6:])
    return staged_inputs, ca.Function("staged_rhs", [x, v, p], [xdot], ["x", "v", "p"], ["xdot"])
