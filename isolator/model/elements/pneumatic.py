"""The pneumatic isolator: an air spring with a damping chamber behind a capillary, and leveling valves.

The equations are the contract of ``docs/scenario-format.md`` ("Pneumatic
isolators and leveling"): chamber pressures are absolute [Pa] and are the
element's internal states (every spring chamber, then every damping chamber);
flows through capillaries follow Hagen-Poiseuille with the mean density,
``mdot = G (pa - pb)(pa + pb) / (2 R T)``, ``G = pi d^4 / (128 mu L)``; a
chamber's pressure follows ``dp/dt = n / V (R T mdot_in - p dV/dt)``. The
valves' dead zone, flow limit and supply/atmosphere cut-offs are written with
``fmin``/``fmax`` and comparisons only, so that the compiled SIMD stepping
loop evaluates them lane by lane.

Literature: Erin, Wilson and Zapfe, "An improved model of a pneumatic
vibration isolator", J. Sound Vib. 218 (1998); Ruzicka and Derby, "Influence
of damping in vibration isolation" (1971), the relaxation isolator.
"""

from __future__ import annotations

import itertools
import math

import casadi as ca

from isolator.model.elements.base import AttachmentMotion, IsolatorElement
from isolator.model.parameters import PneumaticStructure

__all__ = ["PNEUMATIC", "Pneumatic", "capillary_flow", "dead_zone", "sensor_heights"]


def capillary_flow(conductance: ca.SX, pa: ca.SX, pb: ca.SX, rt: ca.SX) -> ca.SX:
    """Mass flow from chamber a to chamber b [kg/s]: ``G (pa - pb)(pa + pb) / (2 R T)``."""
    return conductance * (pa - pb) * (pa + pb) / (2.0 * rt)


def conductance(diameter: ca.SX, length: ca.SX, viscosity: ca.SX) -> ca.SX:
    """``G = pi d^4 / (128 mu L)`` [m^3/(Pa s)]."""
    return math.pi * diameter**4 / (128.0 * viscosity * length)


def dead_zone(error: ca.SX, deadband: ca.SX) -> ca.SX:
    """``sign(e) max(|e| - deadband, 0)``, as ``max(e - b, 0) + min(e + b, 0)`` [m]."""
    return ca.fmax(error - deadband, 0) + ca.fmin(error + deadband, 0)


def sensor_heights(prm: dict[str, ca.SX], pos: ca.SX, rot: ca.SX, n_groups: int) -> list[ca.SX]:
    """World z displacement of each group's sensor point ``(x, y, 0)`` (table frame) from the reference pose [m]."""
    out = []
    for j in range(n_groups):
        point = ca.vertcat(prm["sensor.x"][j], prm["sensor.y"][j], 0)
        out.append((pos + rot @ point - point)[2])
    return out


class Pneumatic(IsolatorElement):
    """Air springs with damping chambers, grouped on leveling valves (states: chamber pressures [Pa])."""

    name = "pneumatic"

    def n_states(self, structure: object) -> int:
        return structure.n_states if isinstance(structure, PneumaticStructure) else 0

    def forces(
        self, prm: dict[str, ca.SX], motion: AttachmentMotion, states: ca.SX | None, preload: ca.SX | None
    ) -> list[ca.SX]:
        if states is None:
            raise ValueError("the pneumatic element needs its chamber pressures")
        p_atm = prm["air.atmosphere"]
        out = []
        for k, (stretch, rate) in enumerate(zip(motion.stretch, motion.rate, strict=True)):
            horizontal = -prm["stiffness"][:, k] * stretch - prm["damping"][:, k] * rate
            out.append(horizontal + ca.vertcat(0, 0, (states[k] - p_atm) * prm["area"][k]))
        return out

    def rates(
        self, prm: dict[str, ca.SX], motion: AttachmentMotion, states: ca.SX, structure: object,
        valves: bool = True,
    ) -> ca.SX:
        """Chamber pressure rates [Pa/s]; ``valves=False``: every valve closed (linear analysis)."""
        if not isinstance(structure, PneumaticStructure):
            raise ValueError("the pneumatic element needs a PneumaticStructure")
        m = len(structure.chambers)
        n, mu = prm["air.polytropic"], prm["air.viscosity"]
        rt = prm["air.gas_constant"] * prm["air.temperature"]
        p_atm = prm["air.atmosphere"]
        p1 = [states[k] for k in range(m)]
        inflow1 = [ca.SX(0) for _ in range(m)]
        rates2 = []
        for k, slot in structure.damping_slots.items():
            p2 = states[m + slot]
            g = conductance(prm["orifice.diameter"][k], prm["orifice.length"][k], mu)
            flow = capillary_flow(g, p2, p1[k], rt)  # damping chamber -> spring chamber
            inflow1[k] += flow
            rates2.append(n / prm["damping_volume"][k] * rt * (-flow))
        heights = sensor_heights(prm, motion.pos, motion.rot, len(structure.groups))
        for j, members in enumerate(structure.groups):
            if len(members) > 1:
                g = conductance(prm["line.diameter"][j], prm["line.length"][j], mu)
                for a, b in itertools.pairwise(members):
                    flow = capillary_flow(g, p1[a], p1[b], rt)
                    inflow1[a] -= flow
                    inflow1[b] += flow
            if valves and structure.valves[j]:
                valve = self.valve_flow(prm, j, heights[j], [p1[k] for k in members], p_atm)
                for k in members:
                    inflow1[k] += valve / len(members)
        rates1 = []
        for k in range(m):
            area = prm["area"][k]
            volume = prm["volume"][k] + area * motion.stretch[k][2]
            rates1.append(n / volume * (rt * inflow1[k] - p1[k] * area * motion.rate[k][2]))
        return ca.vertcat(*rates1, *rates2)

    @staticmethod
    def valve_flow(prm: dict[str, ca.SX], j: int, height: ca.SX, pressures: list[ca.SX], p_atm: ca.SX) -> ca.SX:
        """Mass flow into group ``j`` [kg/s]: ``clip(gain dz(-h), +-max_flow)``, no filling while a spring
        chamber is at or above ``p_atm + supply``, no exhausting while one is at or below ``p_atm``."""
        limit = prm["valve.max_flow"][j]
        demand = prm["valve.gain"][j] * dead_zone(-height, prm["valve.deadband"][j])
        flow = ca.fmin(ca.fmax(demand, -limit), limit)
        highest, lowest = pressures[0], pressures[0]
        for p in pressures[1:]:
            highest, lowest = ca.fmax(highest, p), ca.fmin(lowest, p)
        can_fill = highest < p_atm + prm["supply"][j]
        can_exhaust = lowest > p_atm
        return ca.fmax(flow, 0) * can_fill + ca.fmin(flow, 0) * can_exhaust


#: the pneumatic element
PNEUMATIC = Pneumatic()
