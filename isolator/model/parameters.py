"""The design-parameter vector ``p`` of a model structure: names, order, packing."""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from isolator.scenario.definitions import Scenario

__all__ = ["ParameterLayout"]


@dataclass(frozen=True)
class ParameterLayout:
    """Names and order of the design-parameter vector ``p`` of a model structure.

    Attributes
    ----------
    n_carriages, n_isolators : int
    parents : tuple of int
        Parent index of each carriage (-1: the table); the structure of the chain.
    n_actuators : int
        Force actuators between ground and table.
    ground : bool
        Whether the floor moves (the inputs then hold its motion).
    names : tuple of str
        One name per entry of ``p``, e.g. ``isolators[2].stiffness.z``.

    Notes
    -----
    The model's input vector ``u`` holds, in order: the carriages' coordinates,
    velocities and accelerations (3 n); with ``ground``, the floor's
    displacement ``x, y, z`` [m], rotation ``rx, ry, rz`` [rad] (about the world
    origin) and their rates (12); the actuator forces [N] (``n_actuators``).
    """

    n_carriages: int
    n_isolators: int
    parents: tuple[int, ...]
    n_actuators: int = 0
    ground: bool = False
    names: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        names = ["gravity", "table.mass", "table.inertia.x", "table.inertia.y", "table.inertia.z"]
        names += [f"carriages[{i}].mass" for i in range(self.n_carriages)]
        for key in ("axis", "origin"):
            names += [f"carriages[{i}].{key}.{a}" for i in range(self.n_carriages) for a in "xyz"]
        for key in ("position", "stiffness", "damping"):
            names += [f"isolators[{i}].{key}.{a}" for i in range(self.n_isolators) for a in "xyz"]
        for key in ("position", "direction"):
            names += [f"actuators[{i}].{key}.{a}" for i in range(self.n_actuators) for a in "xyz"]
        object.__setattr__(self, "names", tuple(names))

    @property
    def size(self) -> int:
        return len(self.names)

    @property
    def input_size(self) -> int:
        """Length of the model's input vector ``u``."""
        return 3 * self.n_carriages + (12 if self.ground else 0) + self.n_actuators

    @property
    def ground_slice(self) -> slice:
        """Where the floor's motion sits in ``u`` (empty without ``ground``)."""
        start = 3 * self.n_carriages
        return slice(start, start + (12 if self.ground else 0))

    @property
    def actuator_slice(self) -> slice:
        """Where the actuator forces sit in ``u``."""
        return slice(self.input_size - self.n_actuators, self.input_size)

    def rest_inputs(self, positions: np.ndarray) -> np.ndarray:
        """Inputs ``u`` with the carriages at rest at ``positions`` [m], the floor still, no forces."""
        q = np.asarray(positions, dtype=float).ravel()
        u = np.zeros(self.input_size)
        u[: self.n_carriages] = q
        return u

    @classmethod
    def of(cls, scenario: Scenario) -> ParameterLayout:
        return cls(
            len(scenario.carriages),
            len(scenario.isolators),
            scenario.parent_indices(),
            len(scenario.actuators),
            scenario.has_ground_motion,
        )

    def pack(self, scenario: Scenario) -> np.ndarray:
        """The parameter vector of a scenario with this structure."""
        if ParameterLayout.of(scenario) != self:
            raise ValueError("scenario does not have this model's structure")
        values = [scenario.gravity, scenario.table.mass, *scenario.table.inertia]
        values += [c.mass for c in scenario.carriages]
        values += [v for c in scenario.carriages for v in c.axis]
        values += [v for c in scenario.carriages for v in c.origin]
        for key in ("position", "stiffness", "damping"):
            values += [v for iso in scenario.isolators for v in getattr(iso, key)]
        for key in ("position", "direction"):
            values += [v for act in scenario.actuators for v in getattr(act, key)]
        return np.array(values, dtype=float)

    def unpack(self, p: ca.SX) -> dict[str, ca.SX]:
        """Split a symbolic parameter vector into named blocks."""
        n, m = self.n_carriages, self.n_isolators
        out: dict[str, ca.SX] = {}
        i = 0

        def take(name: str, size: int, cols: int = 1) -> None:
            nonlocal i
            block = p[i : i + size * cols]
            out[name] = ca.reshape(block, size, cols) if cols > 1 else block
            i += size * cols

        take("gravity", 1)
        take("table_mass", 1)
        take("inertia", 3)
        take("masses", n)
        take("axes", 3, n)
        take("origins", 3, n)
        take("positions", 3, m)
        take("stiffness", 3, m)
        take("damping", 3, m)
        take("actuator_positions", 3, self.n_actuators)
        take("actuator_directions", 3, self.n_actuators)
        sizes = {"axes": n, "origins": n, "actuator_positions": self.n_actuators,
                 "actuator_directions": self.n_actuators}
        for k in ("axes", "origins", "positions", "stiffness", "damping", "actuator_positions",
                  "actuator_directions"):
            if sizes.get(k, m) <= 1:
                out[k] = ca.reshape(out[k], 3, sizes.get(k, m))
        return out
