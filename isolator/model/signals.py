"""The table's signals from model states: numpy for results, casadi for compiled loops and sensors.

Table motion is reported as six signals ``x, y, z, rx, ry, rz``: the
displacement of the mass centre [m] and the rotation vector of ``R R_ref^T``
[rad] from a reference state (``docs/scenario-format.md``).
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, Protocol

import casadi as ca
import numpy as np

from isolator.errors import ParameterError
from isolator.model.rotations import quaternion_to_matrix
from isolator.scenario.arguments import check_public

__all__ = [
    "SensedMotion",
    "exact_sensed_motion",
    "relative_rotation_vector",
    "signal_function",
    "signal_jacobian",
    "table_signals",
]

#: terms of the atan(t)/t series in :func:`exact_sensed_motion`
ATAN_TERMS = 8


class SensedMotion(Protocol):
    """Anything that maps a state to the sensed table motion (a model variant)."""

    def sensed_motion(self, x: Any, reference: Any) -> Any:
        """(12,) casadi: displacement, rotation vector, velocity, angular velocity."""


def relative_rotation_vector(quats: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Rotation vectors [rad] of R(q) R(q0)^T for quaternions (w, x, y, z), shape (N, 3).

    ``reference`` is one quaternion (4,) or one per row (N, 4).
    """
    q = quats / np.linalg.norm(quats, axis=1, keepdims=True)
    ref = np.asarray(reference, dtype=float)
    r = ref / np.linalg.norm(ref, axis=-1, keepdims=True)
    w0, v0 = r[..., 0], -r[..., 1:]  # conjugate of the reference
    w, v = q[:, 0], q[:, 1:]
    rel_w = w * w0 - np.sum(v * v0, axis=-1)
    rel_v = w[:, None] * v0 + np.atleast_1d(w0)[..., None] * v + np.cross(v, v0)
    sign = np.where(rel_w < 0, -1.0, 1.0)
    rel_w, rel_v = rel_w * sign, rel_v * sign[:, None]
    norm = np.linalg.norm(rel_v, axis=1)
    angle = 2.0 * np.arctan2(norm, rel_w)
    scale = np.where(norm > 1e-12, angle / np.where(norm > 1e-12, norm, 1.0), 2.0 / rel_w)
    return rel_v * scale[:, None]


def table_signals(states: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """The six table signals (6, N) of states (N, >= 7) holding position and quaternion (w, x, y, z).

    Displacement of the mass centre [m] and rotation vector of R R_ref^T [rad],
    relative to the state ``reference`` (one state, or one per row).

    Parameters
    ----------
    states : ndarray
        (N, >= 7): the table's position [m] and orientation quaternion (w, x, y, z) in its first seven
        entries per row.
    reference : ndarray
        (>= 7,) or (N, >= 7): the state the signals are measured from (one, or one per row).

    Returns
    -------
    ndarray
        (6, N): x, y, z [m] and rx, ry, rz [rad] from the reference.
    """
    states, reference = np.asarray(states, dtype=float), np.asarray(reference, dtype=float)
    if states.ndim != 2 or states.shape[1] < 7:
        raise ParameterError(f"states: must be (N, >= 7) (position, then the quaternion w, x, y, z), got shape "
                             f"{states.shape}")
    rows_ok = reference.ndim == 1 or (reference.ndim == 2 and reference.shape[0] == states.shape[0])
    if not rows_ok or reference.shape[-1] < 7:
        raise ParameterError(f"reference: must be one state (>= 7,) or one per row ({states.shape[0]}, >= 7), got "
                             f"shape {reference.shape}")
    angles = relative_rotation_vector(states[:, 3:7], reference[..., 3:7])
    return np.ascontiguousarray(np.vstack([(states[:, 0:3] - reference[..., 0:3]).T, angles.T]))


def exact_sensed_motion(x: Any, reference: Any) -> Any:
    """The table's motion as ideal inertial sensors report it, (12,).

    Displacement of the mass centre [m] and rotation vector of ``R R_ref^T``
    [rad] from the state ``reference``, then velocity [m/s] and angular
    velocity [rad/s], world axes, of the exact model's state (casadi SX or MX).

    The rotation vector of the relative quaternion ``(w, v)`` is
    ``2 atan(|v|/|w|)/|v| sign(w) v``, written as ``2 v/w`` times the series
    of ``atan(t)/t`` in ``t^2 = |v|^2/w^2`` to ``t^14``: exact to rounding
    (relative error below 1e-15) for rotations up to 0.2 rad, the most a run
    may turn before it is reported as diverged (see
    :func:`relative_rotation_vector` for any angle). It is
    a few times cheaper than ``atan2``, needs no normalisation (it does not
    change when either quaternion is scaled) and is smooth at zero.
    """
    q, r = x[3:7], reference[3:7]
    w0, v0 = r[0], -r[1:4]
    w, v = q[0], q[1:4]
    rel_w = w * w0 - ca.dot(v, v0)
    rel_v = w * v0 + w0 * v + ca.cross(v, v0)
    inverse = 1 / rel_w
    t2 = ca.dot(rel_v, rel_v) * inverse * inverse
    series = 0.0
    for k in range(ATAN_TERMS - 1, -1, -1):  # atan(t)/t = 1 - t^2/3 + t^4/5 - ...
        series = (-1) ** k / (2 * k + 1) + t2 * series
    angles = 2 * inverse * series * rel_v
    omega_world = quaternion_to_matrix(x[3:7]) @ x[10:13]
    return ca.vertcat(x[0:3] - reference[0:3], angles, x[7:10], omega_world)


@lru_cache(maxsize=8)
def signal_function(variant: SensedMotion, n_states: int) -> ca.Function:
    """``(x, reference) -> (6,)``: the six table signals of a state (the first half of
    the variant's ``sensed_motion``), scalar code."""
    x, reference = ca.SX.sym("x", n_states), ca.SX.sym("x_ref", n_states)
    return ca.Function("table_signals", [x, reference], [variant.sensed_motion(x, reference)[:6]])


@lru_cache(maxsize=8)
def signal_jacobian(variant: SensedMotion, n_states: int) -> ca.Function:
    """``(x, reference) -> (6, n_states)``: the six table signals' Jacobian with respect to the state
    [m or rad per state unit]."""
    x, reference = ca.SX.sym("x", n_states), ca.SX.sym("x_ref", n_states)
    return ca.Function("signal_jacobian", [x, reference], [ca.jacobian(variant.sensed_motion(x, reference)[:6], x)])


check_public(globals(), ("table_signals"))
