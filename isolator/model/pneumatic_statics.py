"""What the model variants need of the isolator element: its states' rates, rest states and statics.

For pneumatic tables (``docs/scenario-format.md``, "Pneumatic isolators and
leveling") the static unknowns are the pose and one gauge pressure per
leveling group. The initial equilibrium holds every height sensor at zero
(the level rest pose); the final one holds the sensors of groups with a valve
at zero and keeps the air of the others: ``p^(1/n) V`` summed over a group's
chambers, the air mass times ``R T`` for ``n = 1`` and the quasi-static
(slow, adiabatic) invariant for ``n > 1``.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache

import casadi as ca

from isolator.model.elements.base import IsolatorElement
from isolator.model.elements.pneumatic import PNEUMATIC, sensor_heights
from isolator.model.elements.spring_damper import SPRING_DAMPER
from isolator.model.parameters import ParameterLayout, PneumaticStructure
from isolator.model.residual import attachment_motion, newton_euler_residual
from isolator.model.rotations import cardan_matrix, quaternion_to_matrix

__all__ = [
    "air_contents",
    "air_function",
    "closed_static_function",
    "element_of",
    "element_rates",
    "level_residual",
    "pneumatic_tag",
    "rest_element_states",
]


def element_of(layout: ParameterLayout) -> IsolatorElement:
    """The isolator element of a structure."""
    return PNEUMATIC if layout.pneumatic is not None else SPRING_DAMPER


def pneumatic_tag(structure: PneumaticStructure) -> str:
    """A short identifier of a pneumatic structure for compiled functions' names."""
    return hashlib.sha1(repr(structure).encode()).hexdigest()[:8]


def element_rates(
    layout: ParameterLayout,
    prm: dict[str, ca.SX],
    pos: ca.SX,
    rot: ca.SX,
    vel: ca.SX,
    w_body: ca.SX,
    inner: ca.SX,
    ground: ca.SX | None,
) -> ca.SX:
    """Rates of the element's internal states (empty for spring-dampers)."""
    if layout.pneumatic is None:
        return ca.SX.zeros(0, 1)
    motion = attachment_motion(pos, rot, vel, w_body, prm, ground)
    return PNEUMATIC.rates(prm, motion, inner, layout.pneumatic)


def rest_element_states(layout: ParameterLayout, prm: dict[str, ca.SX], gauge: ca.SX) -> ca.SX:
    """Chamber pressures [Pa] with every chamber of group ``j`` at ``p_atm + gauge[j]``."""
    structure = layout.pneumatic
    if structure is None:
        return ca.SX.zeros(0, 1)
    p1 = [prm["air.atmosphere"] + gauge[j] for j in structure.group_of]
    p2 = [p1[k] for k in structure.damping_slots]
    return ca.vertcat(*p1, *p2)


def _weight_scale(prm: dict[str, ca.SX]) -> ca.SX:
    """[N/m]: makes a height equation comparable with the force equations' tolerance."""
    return prm["gravity"] * prm["table_mass"] + 1.0


def level_residual(layout: ParameterLayout, prm: dict[str, ca.SX], pose: ca.SX) -> ca.SX:
    """Every group's sensor height at the rest ``pose`` (position, Cardan angles), scaled to newtons."""
    if layout.pneumatic is None:
        return ca.SX.zeros(0, 1)
    heights = sensor_heights(prm, pose[:3], cardan_matrix(pose[3:6]), len(layout.pneumatic.groups))
    return ca.vertcat(*heights) * _weight_scale(prm)


def _chamber_volumes(structure: PneumaticStructure, prm: dict[str, ca.SX], pos: ca.SX, rot: ca.SX,
                     ground: ca.SX | None) -> tuple[list[ca.SX], list[ca.SX]]:
    zero = ca.SX.zeros(3, 1)
    motion = attachment_motion(pos, rot, zero, zero, prm, ground)
    v1 = [prm["volume"][k] + prm["area"][k] * motion.stretch[k][2] for k in range(len(structure.chambers))]
    v2 = [prm["damping_volume"][k] for k in structure.damping_slots]
    return v1, v2


def air_contents(structure: PneumaticStructure, prm: dict[str, ca.SX], x: ca.SX) -> ca.SX:
    """Each group's ``sum p^(1/n) V`` over its chambers, of an exact-model state ``x`` [Pa^(1/n) m^3]."""
    m = len(structure.chambers)
    v1, v2 = _chamber_volumes(structure, prm, x[0:3], quaternion_to_matrix(x[3:7]), None)
    inv_n = 1.0 / prm["air.polytropic"]
    slot = structure.damping_slots
    out = []
    for members in structure.groups:
        total = ca.SX(0)
        for k in members:
            total += x[13 + k] ** inv_n * v1[k]
            if k in slot:
                total += x[13 + m + slot[k]] ** inv_n * v2[slot[k]]
        out.append(total)
    return ca.vertcat(*out)


@lru_cache(maxsize=16)
def closed_static_function(layout: ParameterLayout, all_closed: bool = False) -> ca.Function:
    """The final static residual of a pneumatic table: ``(z, c, p, air) -> (r, dr/dz)``.

    ``z`` = (pose, group gauge pressures); groups with a valve hold their
    sensor at zero, the others keep ``air`` (their :func:`air_contents`);
    ``all_closed``: every group keeps its air, valve or not.
    """
    structure = layout.pneumatic
    if structure is None:
        raise ValueError("closed_static_function: not a pneumatic structure")
    n_groups = len(structure.groups)
    p = ca.SX.sym("p", layout.size)
    c = ca.SX.sym("c", layout.input_size)
    z = ca.SX.sym("z", 6 + n_groups)
    air = ca.SX.sym("air", n_groups)
    prm = layout.unpack(p)
    n = layout.n_carriages
    rest = ca.vertcat(c[:n], ca.SX.zeros(layout.input_size - n, 1))
    rot = cardan_matrix(z[3:6])
    zero3 = ca.SX.zeros(3, 1)
    states = rest_element_states(layout, prm, z[6:])
    force = newton_euler_residual(
        z[:3], rot, zero3, zero3, zero3, zero3, rest[: 3 * n], prm, layout.parents,
        element=PNEUMATIC, element_states=states,
    )
    heights = sensor_heights(prm, z[:3], rot, n_groups)
    v1, v2 = _chamber_volumes(structure, prm, z[:3], rot, None)
    slot = structure.damping_slots
    inv_n = 1.0 / prm["air.polytropic"]
    scale = _weight_scale(prm)
    extra = []
    for j, members in enumerate(structure.groups):
        if structure.valves[j] and not all_closed:
            extra.append(heights[j] * scale)
            continue
        volume = sum((v1[k] + (v2[slot[k]] if k in slot else 0) for k in members), ca.SX(0))
        content = (prm["air.atmosphere"] + z[6 + j]) ** inv_n * volume
        extra.append((content / air[j] - 1.0) * prm["gravity"] * (prm["table_mass"] + 1.0))
    r = ca.vertcat(force, *extra)
    return ca.Function("closed_static", [z, c, p, air], [r, ca.jacobian(r, z), ca.jacobian(r, air)],
                       ["z", "c", "p", "air"], ["r", "drdz", "drdair"])


@lru_cache(maxsize=16)
def air_function(layout: ParameterLayout) -> ca.Function:
    """``(x, p) -> air``: each group's :func:`air_contents` of an exact-model state."""
    structure = layout.pneumatic
    if structure is None:
        raise ValueError("air_function: not a pneumatic structure")
    n_states = 13 + structure.n_states
    x, p = ca.SX.sym("x", n_states), ca.SX.sym("p", layout.size)
    return ca.Function("air", [x, p], [air_contents(structure, layout.unpack(p), x)], ["x", "p"], ["air"])
