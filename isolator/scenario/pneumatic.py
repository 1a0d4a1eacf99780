"""Pneumatic isolators and leveling groups: their frozen dataclasses and the statics that size them.

The keys, rules and equations are the contract of ``docs/scenario-format.md``,
section "Pneumatic isolators and leveling". An air spring (spring chamber of
volume ``V1r`` closed by a piston of effective area ``A``) is joined through a
capillary orifice to a damping chamber ``V2``; groups of isolators share one
leveling valve and a connecting line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from isolator.scenario.arguments import check_public

__all__ = [
    "Air",
    "Capillary",
    "LevelingGroup",
    "PneumaticIsolator",
    "Valve",
    "group_statics_matrix",
]

Vector3 = tuple[float, float, float]


@dataclass(frozen=True)
class Air:
    """The air in every chamber.

    Attributes
    ----------
    atmosphere : float
        Absolute ambient pressure [Pa].
    temperature : float
        [K].
    gas_constant : float
        Specific gas constant R [J/(kg K)].
    viscosity : float
        Dynamic viscosity mu [Pa s].
    polytropic : float
        Exponent n, 1 (isothermal) .. 1.4 (adiabatic) [-].
    """

    atmosphere: float = 101325.0
    temperature: float = 293.15
    gas_constant: float = 287.05
    viscosity: float = 1.81e-5
    polytropic: float = 1.4


@dataclass(frozen=True)
class Capillary:
    """A capillary (laminar, Hagen-Poiseuille) between two chambers.

    Attributes
    ----------
    diameter, length : float
        [m].
    """

    diameter: float
    length: float

    def conductance(self, viscosity: float) -> float:
        """``G = pi d^4 / (128 mu L)`` [m^3/(Pa s)], so that the mass flow is ``G (pa - pb)(pa + pb) / (2 R T)``."""
        return math.pi * self.diameter**4 / (128.0 * viscosity * self.length)


@dataclass(frozen=True)
class PneumaticIsolator:
    """An air spring with a damping chamber behind a capillary orifice; a spring-damper horizontally.

    Attributes
    ----------
    name : str
    position : tuple of float
        Attachment point in the table frame [m].
    area : float
        Effective piston area A [m^2].
    volume : float
        Spring chamber volume at the rest pose V1r [m^3].
    damping_volume : float
        Damping chamber volume V2 [m^3]; 0: a plain air spring.
    orifice : Capillary or None
        Between the chambers (None only without a damping chamber).
    horizontal_stiffness, horizontal_damping : tuple of float
        Along world x and y [N/m], [N s/m].
    """

    name: str
    position: Vector3
    area: float
    volume: float
    damping_volume: float
    orifice: Capillary | None
    horizontal_stiffness: tuple[float, float]
    horizontal_damping: tuple[float, float]

    @property
    def has_damping_chamber(self) -> bool:
        return self.damping_volume > 0.0

    def scaled(self, stiffness: float, damping: float) -> PneumaticIsolator:
        """The isolator with its springs scaled by ``stiffness`` and its dampers by ``damping``.

        As a three-parameter element (the spring ``k_0`` in parallel with the spring ``k_b`` in series with
        the orifice's dashpot ``c_b = A^2 V2^2 / (V1r (V1r + V2) G)``): both volumes divided by ``stiffness``,
        the orifice's conductance ``G ~ d^4`` divided by ``stiffness * damping``; the horizontal spring and
        damper scaled directly. :func:`isolator.simulation.scaling.scaled_parameter_sets` does the same to
        parameter vectors.
        """
        orifice = self.orifice
        if orifice is not None:
            orifice = Capillary(orifice.diameter * (stiffness * damping) ** -0.25, orifice.length)
        kx, ky = self.horizontal_stiffness
        cx, cy = self.horizontal_damping
        return replace(self, volume=self.volume / stiffness, damping_volume=self.damping_volume / stiffness,
                       orifice=orifice, horizontal_stiffness=(stiffness * kx, stiffness * ky),
                       horizontal_damping=(damping * cx, damping * cy))

    def vertical_stiffness(self, gauge_pressure: float, air: Air) -> float:
        """Small-amplitude stiffness of the air spring alone (orifice closed) [N/m]: ``n p0 A^2 / V1r``."""
        return air.polytropic * (gauge_pressure + air.atmosphere) * self.area**2 / self.volume


@dataclass(frozen=True)
class Valve:
    """A group's height-control (leveling) valve.

    Attributes
    ----------
    gain : float
        Mass flow per height error outside the dead band [kg/(s m)].
    deadband : float
        Half-width of the dead zone [m].
    max_flow : float
        Largest mass flow in or out [kg/s].
    """

    gain: float
    deadband: float
    max_flow: float


@dataclass(frozen=True)
class LevelingGroup:
    """Pneumatic isolators sharing one leveling valve and a connecting line.

    Attributes
    ----------
    name : str
    isolators : tuple of int
        Indices into the scenario's isolators, in the listed order.
    line : Capillary or None
        The capillary joining each consecutive pair of the group's spring chambers.
    sensor : tuple of float
        (x, y) of the height sensor in the table frame [m].
    valve : Valve or None
        None: the group's air mass stays fixed.
    supply : float
        Gauge supply pressure of the valve [Pa].
    """

    name: str
    isolators: tuple[int, ...]
    line: Capillary | None
    sensor: tuple[float, float]
    valve: Valve | None = None
    supply: float = 6.0e5


def group_statics_matrix(
    isolators: tuple[PneumaticIsolator, ...], groups: tuple[LevelingGroup, ...]
) -> np.ndarray:
    """Vertical force and moments per unit gauge pressure of each group at the rest pose, (3, groups).

    Rows: total vertical force [N/Pa], its moment ``sum A y`` about x and ``sum A x``
    about -y [N m/Pa] (table frame at the reference pose). With the weight's
    ``(W, W y_G, W x_G)`` on the right, solving gives the group pressures that
    hold the table level.
    """
    out = np.zeros((3, len(groups)))
    for j, group in enumerate(groups):
        for k in group.isolators:
            iso = isolators[k]
            out[:, j] += iso.area * np.array([1.0, iso.position[1], iso.position[0]])
    return out


check_public(globals(), ("Air", "Capillary", "LevelingGroup", "PneumaticIsolator", "Valve"))
