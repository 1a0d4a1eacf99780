"""The interface every isolator element implements: its parameters, forces, preload and internal states.

An element turns the motion of the isolators' attachment points (relative to
their floor points) into the forces on the table, and may carry internal
states with their own rates (the pneumatic element's chamber pressures). The
residual (:func:`isolator.model.residual.newton_euler_residual`) adds the
forces; the model variants append the internal states after the table's.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import casadi as ca

__all__ = ["AttachmentMotion", "IsolatorElement"]


@dataclass(frozen=True)
class AttachmentMotion:
    """Where the isolators' attachment points are, relative to their floor points.

    Attributes
    ----------
    stretch : list of SX (3,)
        Displacement of each attachment point from its reference position,
        less the floor's motion there, world axes [m].
    rate : list of SX (3,)
        Its rate [m/s].
    pos : SX (3,)
        The table's mass centre from the reference pose [m].
    rot : SX (3, 3)
        The table's orientation (table to world).
    """

    stretch: list[ca.SX]
    rate: list[ca.SX]
    pos: ca.SX
    rot: ca.SX


class IsolatorElement(ABC):
    """One kind of isolator. Subclass it in a module of its own in :mod:`isolator.model.elements`."""

    #: the scenario's ``model`` key for this kind
    name: str

    @abstractmethod
    def n_states(self, structure: object) -> int:
        """How many internal states the isolators of a structure carry (0: none)."""

    @abstractmethod
    def forces(
        self, prm: dict[str, ca.SX], motion: AttachmentMotion, states: ca.SX | None, preload: ca.SX | None
    ) -> list[ca.SX]:
        """Force of each isolator on the table at its attachment point, world axes [N], (3,) each.

        ``preload`` is the vertical static force of each isolator (spring-damper;
        None: unloaded springs), ``states`` the internal states (None without).
        """

    def rates(
        self, prm: dict[str, ca.SX], motion: AttachmentMotion, states: ca.SX, structure: object,
        valves: bool = True,
    ) -> ca.SX:
        """Rates of the internal states (empty for an element without states); ``valves=False``: any
        valve closed, as linear analysis treats them."""
        return ca.SX.zeros(0, 1)
