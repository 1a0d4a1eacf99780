"""Force actuators between floor and table (``[[actuators]]``) and named points of the table (``[[points]]``)."""

from __future__ import annotations

from dataclasses import dataclass

from isolator.scenario.flexible.reader import Feet, tupled_feet
from isolator.scenario.random_sources import SpectralDensity

__all__ = ["Actuator", "Point"]

#: a 3-vector [SI units]
Vector3 = tuple[float, float, float]


@dataclass(frozen=True)
class Actuator:
    """A force actuator between ground and table.

    Attributes
    ----------
    name : str
    position : tuple of float
        Point of action in the table frame [m].
    direction : tuple of float
        Unit line of action in the world frame.
    max_force : float
        Symmetric limit [N].
    bandwidth : float or None
        First-order lag corner [Hz], if any.
    max_rate : float or None
        Largest rate of change of the command [N/s], if any (respected by
        optimised feedforward; commands from files are not rate limited).
    noise_psd : SpectralDensity or None
        One-sided PSD [N^2/Hz] of a random force added to the force the actuator applies (after clipping
        and lag), a source of the error budget.
    """

    name: str
    position: Vector3
    direction: Vector3
    max_force: float
    bandwidth: float | None = None
    max_rate: float | None = None
    noise_psd: SpectralDensity | None = None


@dataclass(frozen=True)
class Point:
    """A point of interest on the table, whose motion linear analyses report.

    Attributes
    ----------
    name : str
    position : tuple of float
        In the table frame [m].
    feet : tuple of (float, float) or None
        Where a thing at the point stands on a bending top (a bridge): (x, y) offsets from it [m]; None: one
        foot at the point.
    """

    name: str
    position: Vector3
    feet: Feet | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "feet", tupled_feet(self.feet))
