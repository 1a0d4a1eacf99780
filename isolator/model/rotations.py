"""Rotation helpers for the casadi model: cross-product matrix, quaternions, Cardan angles."""

from __future__ import annotations

import casadi as ca
import numpy as np

__all__ = [
    "cardan_matrix",
    "cardan_to_quaternion",
    "pose_rotation",
    "quaternion_rate",
    "quaternion_to_matrix",
    "skew",
]


def skew(v: ca.SX) -> ca.SX:
    """Cross-product matrix [v]x of a 3-vector."""
    return ca.vertcat(
        ca.horzcat(0, -v[2], v[1]),
        ca.horzcat(v[2], 0, -v[0]),
        ca.horzcat(-v[1], v[0], 0),
    )


def quaternion_to_matrix(qt: ca.SX) -> ca.SX:
    """Rotation matrix of a quaternion (w, x, y, z), normalised on the fly."""
    w, x, y, z = qt[0], qt[1], qt[2], qt[3]
    s = 2.0 / (w * w + x * x + y * y + z * z)
    return ca.vertcat(
        ca.horzcat(1 - s * (y * y + z * z), s * (x * y - w * z), s * (x * z + w * y)),
        ca.horzcat(s * (x * y + w * z), 1 - s * (x * x + z * z), s * (y * z - w * x)),
        ca.horzcat(s * (x * z - w * y), s * (y * z + w * x), 1 - s * (x * x + y * y)),
    )


def quaternion_rate(qt: ca.SX, w_body: ca.SX) -> ca.SX:
    """d/dt of a quaternion (w, x, y, z) for a body-frame angular velocity [rad/s]."""
    w, x, y, z = qt[0], qt[1], qt[2], qt[3]
    p, q, r = w_body[0], w_body[1], w_body[2]
    return 0.5 * ca.vertcat(
        -x * p - y * q - z * r,
        w * p + y * r - z * q,
        w * q + z * p - x * r,
        w * r + x * q - y * p,
    )


def cardan_matrix(th: ca.SX) -> ca.SX:
    """R = Rz(th[2]) Ry(th[1]) Rx(th[0]); equal to I + [th]x to first order."""
    cx, sx = ca.cos(th[0]), ca.sin(th[0])
    cy, sy = ca.cos(th[1]), ca.sin(th[1])
    cz, sz = ca.cos(th[2]), ca.sin(th[2])
    rx = ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, cx, -sx), ca.horzcat(0, sx, cx))
    ry = ca.vertcat(ca.horzcat(cy, 0, sy), ca.horzcat(0, 1, 0), ca.horzcat(-sy, 0, cy))
    rz = ca.vertcat(ca.horzcat(cz, -sz, 0), ca.horzcat(sz, cz, 0), ca.horzcat(0, 0, 1))
    return rz @ ry @ rx


def pose_rotation(angles: np.ndarray) -> np.ndarray:
    """Numeric Rz Ry Rx of Cardan angles (rx, ry, rz) [rad], e.g. of an equilibrium pose, (3, 3)."""
    angles_sym = ca.SX.sym("a", 3)
    numeric = ca.Function("pose_rotation", [angles_sym], [cardan_matrix(angles_sym)])
    return np.asarray(numeric(np.asarray(angles, dtype=float)), dtype=float)



def cardan_to_quaternion(th: ca.SX) -> ca.SX:
    """Quaternion (w, x, y, z) of Rz(th2) Ry(th1) Rx(th0)."""
    cr, sr = ca.cos(th[0] / 2), ca.sin(th[0] / 2)
    cp, sp = ca.cos(th[1] / 2), ca.sin(th[1] / 2)
    cy, sy = ca.cos(th[2] / 2), ca.sin(th[2] / 2)
    return ca.vertcat(
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )
