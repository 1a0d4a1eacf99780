"""The spring-damper isolator: a fixed stiffness and damping per world axis, with its static preload."""

from __future__ import annotations

import casadi as ca

__all__ = ["isolator_preloads"]


def isolator_preloads(prm: dict[str, ca.SX], carriage_mass: ca.SX) -> ca.SX:
    """Vertical static force of each isolator at the reference pose [N], (3, m).

    Every isolator has the same free height: its zero-force point lies
    ``delta = g m_total / sum(k_z)`` above its attachment point at the
    reference pose (table mass centre at the origin, axes level), so the
    isolators together carry the whole weight there.
    """
    kz = prm["stiffness"][2, :]
    weight = prm["gravity"] * (prm["table_mass"] + carriage_mass)
    delta = weight / ca.fmax(ca.sum2(kz), 1e-300)
    m = kz.shape[1]
    return ca.vertcat(ca.SX.zeros(2, m), kz * delta)
