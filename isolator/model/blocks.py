"""Solving the table's 6 x 6 mass-matrix systems by blocks (symbolic, casadi)."""

from __future__ import annotations

import casadi as ca

__all__ = ["solve_blocks"]


def solve_blocks(mass: ca.SX, rhs: ca.SX) -> ca.SX:
    """Solve the 6x6 (translation, rotation) system by its 3x3 Schur complement."""
    a_tt, a_tr = mass[:3, :3], mass[:3, 3:]
    a_rt, a_rr = mass[3:, :3], mass[3:, 3:]
    inv_tt = ca.inv(a_tt)
    schur = a_rr - a_rt @ inv_tt @ a_tr
    alpha = ca.solve(schur, rhs[3:, :] - a_rt @ inv_tt @ rhs[:3, :])
    acc = inv_tt @ (rhs[:3, :] - a_tr @ alpha)
    return ca.vertcat(acc, alpha)
