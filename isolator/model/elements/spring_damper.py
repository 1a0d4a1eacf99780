"""The spring-damper isolator: a fixed stiffness and damping per world axis, with its static preload."""

from __future__ import annotations

import casadi as ca

from isolator.model.elements.base import AttachmentMotion, IsolatorElement

__all__ = ["SPRING_DAMPER", "SpringDamper", "isolator_preloads"]


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


class SpringDamper(IsolatorElement):
    """``F0 - K (P - P_ref) - C dP/dt`` along the world axes (``docs/scenario-format.md``)."""

    name = "spring-damper"

    def n_states(self, structure: object) -> int:
        return 0

    def forces(
        self, prm: dict[str, ca.SX], motion: AttachmentMotion, states: ca.SX | None, preload: ca.SX | None
    ) -> list[ca.SX]:
        out = []
        for k, (stretch, rate) in enumerate(zip(motion.stretch, motion.rate, strict=True)):
            f = -prm["stiffness"][:, k] * stretch - prm["damping"][:, k] * rate
            out.append(f if preload is None else f + preload[:, k])
        return out


#: the spring-damper element
SPRING_DAMPER = SpringDamper()
