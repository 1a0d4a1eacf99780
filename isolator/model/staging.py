"""The exact model's right-hand side split in two: a time-only part shared by many runs, and the rest.

What depends on time only (the carriages' mass moments and the inverse mass
matrix, then the floor's motion and the actuator forces) is computed once per
stage time as ``v = staged_inputs(c, p)``; ``staged_rhs(x, v, p)`` then gives
``dx/dt`` for many runs of a batch.
"""

from __future__ import annotations

import casadi as ca

from isolator.model.parameters import ParameterLayout
from isolator.model.pneumatic_statics import element_of, element_rates
from isolator.model.residual import carriage_kinematics, newton_euler_residual, solve_blocks
from isolator.model.rotations import quaternion_rate

__all__ = ["TIME_ONLY", "staged_functions"]


def _upper(m: ca.SX) -> ca.SX:
    """The upper triangle of a symmetric matrix, row by row."""
    n = m.shape[0]
    return ca.vertcat(*[m[i, j] for i in range(n) for j in range(i, n)])


def _symmetric(values: ca.SX, n: int) -> ca.SX:
    """Inverse of :func:`_upper`."""
    out = ca.SX.zeros(n, n)
    k = 0
    for i in range(n):
        for j in range(i, n):
            out[i, j] = out[j, i] = values[k]
            k += 1
    return out


#: time-only values of the staged exact model: (name, packed size); ``Jc`` and the inverse mass matrix
#: ``Minv`` are symmetric, stored as upper triangles
TIME_ONLY = (("S", 3), ("Sd", 3), ("Sdd", 3), ("Jc", 6), ("Hd", 3), ("B", 9), ("Minv", 21))


def _pack_time_only(kin: dict[str, ca.SX], inv_mass: ca.SX) -> ca.SX:
    parts = {**kin, "Jc": _upper(kin["Jc"]), "B": ca.vec(kin["B"]), "Minv": _upper(inv_mass)}
    return ca.vertcat(*[parts[name] for name, _ in TIME_ONLY])


def _unpack_time_only(packed: ca.SX, carriage_mass: ca.SX) -> tuple[dict[str, ca.SX], ca.SX]:
    """The carriage moments (with their constant total mass) and the inverse mass matrix."""
    out, i = {"m": carriage_mass}, 0
    for name, size in TIME_ONLY:
        block = packed[i : i + size]
        out[name] = {"Jc": lambda b: _symmetric(b, 3), "B": lambda b: ca.reshape(b, 3, 3),
                     "Minv": lambda b: _symmetric(b, 6)}.get(name, lambda b: b)(block)
        i += size
    inv_mass = out.pop("Minv")
    return out, inv_mass



def staged_functions(
    layout: ParameterLayout,
    x: ca.SX,
    rot: ca.SX,
    acc_vars: ca.SX,
    c: ca.SX,
    p: ca.SX,
    prm: dict[str, ca.SX],
    extra: dict[str, ca.SX | None],
) -> tuple[ca.Function, ca.Function]:
    """The exact model's right-hand side with its time-only part (moments, inverse mass matrix) as inputs."""
    n = layout.n_carriages
    size = sum(k for _, k in TIME_ONLY)
    rest = c[3 * n :]
    v = ca.SX.sym("v", size + rest.shape[0])
    kin, inv_mass = _unpack_time_only(v[:size], ca.sum1(prm["masses"]))
    moved = {k: None if e is None else ca.substitute(e, rest, v[size:]) for k, e in extra.items()}
    pos, qt, vel, w, inner = x[0:3], x[3:7], x[7:10], x[10:13], x[13:]
    element = element_of(layout)
    states = inner if inner.shape[0] else None
    res = newton_euler_residual(
        pos, rot, vel, w, acc_vars[:3], acc_vars[3:], None, prm, layout.parents, kin=kin,
        ground=moved["ground"], actuator_forces=moved["actuator_forces"],
        element=element, element_states=states,
    )
    bias = ca.substitute(res, acc_vars, ca.SX.zeros(6, 1))
    accel = -inv_mass @ bias
    inner_rates = element_rates(layout, prm, pos, rot, vel, w, inner, moved["ground"])
    xdot = ca.vertcat(vel, quaternion_rate(qt, w), rot @ accel[:3], accel[3:], inner_rates)
    moments = carriage_kinematics(c[: 3 * n], prm, layout.parents)
    mass = ca.jacobian(newton_euler_residual(
        pos, rot, vel, w, acc_vars[:3], acc_vars[3:], None, prm, layout.parents, kin=moments,
        ground=extra["ground"], actuator_forces=extra["actuator_forces"],
        element=element, element_states=states,
    ), acc_vars)
    inputs = ca.vertcat(_pack_time_only(moments, solve_blocks(mass, ca.SX.eye(6))), rest)
    return (
        ca.Function("staged_inputs", [c, p], [inputs], ["c", "p"], ["v"]),
        ca.Function("staged_rhs", [x, v, p], [xdot], ["x", "v", "p"], ["xdot"]),
    )
