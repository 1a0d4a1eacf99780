"""The design-parameter vector ``p`` of a model structure: names, order, packing."""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from isolator.errors import ParameterError, ScenarioError
from isolator.model.flexible.structure import ElasticStructure
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Isolator, Scenario
from isolator.scenario.pneumatic import PneumaticIsolator
from isolator.scenario.rules import check_parameters, check_scenario_values, check_value, closest
from isolator.scenario.validation import check_carriage_tree, check_isolator_layout

__all__ = ["AIR_KEYS", "ParameterLayout", "PneumaticStructure"]

#: parameters that place things on the top (a bending top's shapes are taken there when the model is built)
_GEOMETRY = re.compile(r"^(isolators\[\d+\]\.position|actuators\[\d+\]\.position|carriages\[\d+\]\.(origin|axis))\.")
#: the ``[air]`` keys, in the parameter vector's order
AIR_KEYS = ("atmosphere", "temperature", "gas_constant", "viscosity", "polytropic")
_VALVE_KEYS = ("gain", "deadband", "max_flow")


@dataclass(frozen=True)
class PneumaticStructure:
    """What fixes a pneumatic model's states and equations (its numbers stay parameters).

    Attributes
    ----------
    groups : tuple of tuple of int
        The isolators of each leveling group, in the listed order.
    valves : tuple of bool
        Whether each group has a leveling valve.
    chambers : tuple of bool
        Whether each isolator has a damping chamber.
    """

    groups: tuple[tuple[int, ...], ...]
    valves: tuple[bool, ...]
    chambers: tuple[bool, ...]

    @property
    def n_states(self) -> int:
        """Spring-chamber pressures, then damping-chamber pressures [Pa]."""
        return len(self.chambers) + sum(self.chambers)

    @property
    def damping_slots(self) -> dict[int, int]:
        """Isolator index -> its damping chamber's place among the damping chambers (whose pressures
        follow the spring chambers' in the states), for the isolators that have one, in order."""
        return {k: s for s, k in enumerate(k for k, d in enumerate(self.chambers) if d)}

    @property
    def group_of(self) -> tuple[int, ...]:
        """The leveling group of each isolator."""
        owner = {k: j for j, members in enumerate(self.groups) for k in members}
        return tuple(owner[k] for k in range(len(self.chambers)))

    def names(self) -> list[str]:
        """Parameter names of the isolators, groups and air, in order."""
        out: list[str] = []
        for i, damped in enumerate(self.chambers):
            out += [f"isolators[{i}].position.{a}" for a in "xyz"]
            out += [f"isolators[{i}].{k}" for k in ("area", "volume", "damping_volume")]
            if damped:
                out += [f"isolators[{i}].orifice.diameter", f"isolators[{i}].orifice.length"]
            out += [f"isolators[{i}].horizontal_stiffness.{a}" for a in "xy"]
            out += [f"isolators[{i}].horizontal_damping.{a}" for a in "xy"]
        for j, (members, valve) in enumerate(zip(self.groups, self.valves, strict=True)):
            if len(members) > 1:
                out += [f"leveling[{j}].line.diameter", f"leveling[{j}].line.length"]
            out += [f"leveling[{j}].sensor.x", f"leveling[{j}].sensor.y", f"leveling[{j}].supply"]
            if valve:
                out += [f"leveling[{j}].valve.{k}" for k in _VALVE_KEYS]
        return out + [f"air.{k}" for k in AIR_KEYS]

    @classmethod
    def of(cls, scenario: Scenario) -> PneumaticStructure | None:
        if not scenario.is_pneumatic:
            return None
        return cls(
            tuple(g.isolators for g in scenario.leveling),
            tuple(g.valve is not None for g in scenario.leveling),
            tuple(isinstance(iso, PneumaticIsolator) and iso.has_damping_chamber for iso in scenario.isolators),
        )

    def pack(self, scenario: Scenario) -> list[float]:
        """The values of :meth:`names` for a scenario of this structure."""
        out: list[float] = []
        for iso in scenario.isolators:
            if not isinstance(iso, PneumaticIsolator):
                raise ValueError("scenario does not have this model's structure")
            out += [*iso.position, iso.area, iso.volume, iso.damping_volume]
            if iso.has_damping_chamber and iso.orifice is not None:
                out += [iso.orifice.diameter, iso.orifice.length]
            out += [*iso.horizontal_stiffness, *iso.horizontal_damping]
        for g in scenario.leveling:
            if len(g.isolators) > 1 and g.line is not None:
                out += [g.line.diameter, g.line.length]
            out += [*g.sensor, g.supply]
            if g.valve is not None:
                out += [g.valve.gain, g.valve.deadband, g.valve.max_flow]
        air = scenario.air
        if air is None:
            raise ValueError("scenario does not have this model's structure")
        return out + [getattr(air, k) for k in AIR_KEYS]

    def unpack(self, block: ca.SX) -> dict[str, ca.SX]:
        """Named symbols of the pneumatic block: per isolator ``area, volume, damping_volume, orifice``
        (conductance-defining diameter and length, or zeros), ``positions`` (3, m), ``stiffness`` and
        ``damping`` (3, m; zero vertically), per group ``line``, ``sensor``, ``supply``, ``valve``; ``air``."""
        values = dict(zip(self.names(), ca.vertsplit(block), strict=True))
        m = len(self.chambers)
        zero = ca.SX(0)

        def iso(i: int, key: str) -> ca.SX:
            return values.get(f"isolators[{i}].{key}", zero)

        def column(i: int, key: str) -> ca.SX:
            return ca.vertcat(iso(i, f"{key}.x"), iso(i, f"{key}.y"), zero) if key != "position" else \
                ca.vertcat(*[iso(i, f"position.{a}") for a in "xyz"])

        out: dict[str, ca.SX] = {
            "positions": ca.horzcat(*[column(i, "position") for i in range(m)]),
            "stiffness": ca.horzcat(*[column(i, "horizontal_stiffness") for i in range(m)]),
            "damping": ca.horzcat(*[column(i, "horizontal_damping") for i in range(m)]),
        }
        for key in ("area", "volume", "damping_volume", "orifice.diameter", "orifice.length"):
            out[key] = ca.vertcat(*[iso(i, key) for i in range(m)])
        for key in ("line.diameter", "line.length", "sensor.x", "sensor.y", "supply", "valve.gain",
                    "valve.deadband", "valve.max_flow"):
            out[key] = ca.vertcat(*[values.get(f"leveling[{j}].{key}", zero) for j in range(len(self.groups))])
        for key in AIR_KEYS:
            out[f"air.{key}"] = values[f"air.{key}"]
        return out


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
    pneumatic : PneumaticStructure or None
        The pneumatic isolators' structure (groups, valves, chambers); None for spring-dampers.
    flexible : ElasticStructure or None
        A bending top's modes and their shapes where things touch it (``[table.flexible]``); None for a
        rigid top.

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
    pneumatic: PneumaticStructure | None = None
    flexible: ElasticStructure | None = None
    names: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        names = ["gravity", "table.mass", "table.inertia.x", "table.inertia.y", "table.inertia.z"]
        names += [f"carriages[{i}].mass" for i in range(self.n_carriages)]
        for key in ("axis", "origin"):
            names += [f"carriages[{i}].{key}.{a}" for i in range(self.n_carriages) for a in "xyz"]
        if self.pneumatic is None:
            for key in ("position", "stiffness", "damping"):
                names += [f"isolators[{i}].{key}.{a}" for i in range(self.n_isolators) for a in "xyz"]
        for key in ("position", "direction"):
            names += [f"actuators[{i}].{key}.{a}" for i in range(self.n_actuators) for a in "xyz"]
        if self.pneumatic is not None:
            names += self.pneumatic.names()
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
        """The layout of a scenario, checked as the file reader checks it (for scenarios built from the
        dataclasses directly): every number by :mod:`isolator.scenario.rules`, the carriage chain and the
        isolators' layout; a :class:`ScenarioError` naming the key."""
        check_scenario_values(scenario)
        check_carriage_tree(scenario.carriages)
        check_isolator_layout(scenario.isolators)
        flexible = ElasticStructure.of(scenario)
        if flexible is not None and scenario.is_pneumatic:
            raise ScenarioError("table.flexible: a bending top on pneumatic isolators is not modelled yet; "
                                "give the isolators as springs and dampers (their stiffness and damping at rest)")
        return cls(
            len(scenario.carriages),
            len(scenario.isolators),
            scenario.parent_indices(),
            len(scenario.actuators),
            scenario.has_ground_motion,
            PneumaticStructure.of(scenario),
            flexible,
        )

    def pack(self, scenario: Scenario) -> np.ndarray:
        """The parameter vector of a scenario with this structure."""
        if ParameterLayout.of(scenario) != self:
            raise ValueError("scenario does not have this model's structure")
        values = [scenario.gravity, scenario.table.mass, *scenario.table.inertia]
        values += [c.mass for c in scenario.carriages]
        values += [v for c in scenario.carriages for v in c.axis]
        values += [v for c in scenario.carriages for v in c.origin]
        if self.pneumatic is None:
            for key in ("position", "stiffness", "damping"):
                values += [v for iso in scenario.isolators for v in getattr(iso, key)]
        for key in ("position", "direction"):
            values += [v for act in scenario.actuators for v in getattr(act, key)]
        if self.pneumatic is not None:
            values += self.pneumatic.pack(scenario)
        return np.array(values, dtype=float)

    # -- checks of parameter vectors given as arguments --------------------------------------------------
    def checked(self, p: object, argument: str = "p") -> np.ndarray:
        """A whole parameter vector given as an argument, as floats, checked entry by entry.

        Raises
        ------
        ParameterError
            Naming the argument for a wrong shape, else the entry and its parameter:
            ``p[17] (isolators[0].damping.z): must be >= 0, got -5``.
        """
        expected = f"must be a vector of {self.size} numbers (Simulator.layout.names)"
        try:
            array = np.array(p, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(f"{argument}: {expected}, got {type(p).__name__}") from None
        if array.shape != (self.size,):
            raise ParameterError(f"{argument}: {expected}, got shape {array.shape}")
        self.check(array, lambda i: f"{argument}[{i}] ({self.names[i]})",
                   vector_key=lambda at, head: f"{argument}[{at[0]}:{at[-1] + 1}] ({head})")
        return array

    def with_changes(self, p: np.ndarray, changes: Mapping[str, float] | None, argument: str = "changes"
                     ) -> np.ndarray:
        """A copy of ``p`` with named entries changed, each checked by its rule.

        Raises
        ------
        ParameterError
            ``changes['isolators[0].damping.z']: must be >= 0, got -5``; an unknown name with the
            closest valid one.
        """
        out = np.array(p, dtype=float)
        if changes is None:
            return out
        if not isinstance(changes, Mapping):
            raise ParameterError(f"{argument}: must be a mapping of parameter names to values, "
                                 f"got {type(changes).__name__}")
        index = {n: i for i, n in enumerate(self.names)}
        changed: list[int] = []
        for name, value in changes.items():
            if not isinstance(name, str) or name not in index:
                near = closest(str(name), self.names)
                hint = f"; did you mean '{near}'?" if near else ""
                raise ParameterError(f"{argument}[{name!r}]: not a parameter of this scenario{hint} "
                                     "(Simulator.layout.names lists them)")
            i = index[name]
            if self.flexible is not None and _GEOMETRY.match(name):
                raise ParameterError(f"{argument}[{name!r}]: the top bends ([table.flexible]): its modes' shapes "
                                     "were taken where the scenario puts things on it; change the scenario instead")
            out[i] = check_value(name, value, f"{argument}[{name!r}]", ParameterError)
            changed.append(i)
        self.check(out, lambda i: f"{argument}[{self.names[i]!r}]", changed)
        return out

    def check(self, p: np.ndarray, key: Callable[[int], str], entries: Sequence[int] | None = None,
              vector_key: Callable[[list[int], str], str] | None = None) -> None:
        """Entries of ``p`` (default all) by their rules, and what they make together: unit directions,
        the inertia's triangle, the isolators off one line, damping chambers as the model was built
        (errors start with ``key(i)``, or ``vector_key(entries, name)`` for a whole vector)."""
        check_parameters(self.names, p, key, ParameterError, entries, vector_key)
        which = set(range(self.size) if entries is None else entries)
        if self.pneumatic is not None:
            for i, damped in enumerate(self.pneumatic.chambers):
                at = self.names.index(f"isolators[{i}].damping_volume")
                if at in which and (p[at] > 0) != damped:
                    raise ParameterError(
                        f"{key(at)}: must be {'> 0' if damped else '0'}, got {p[at]:g} (the model was built "
                        f"{'with' if damped else 'without'} a damping chamber here; change the scenario instead)")
        at_positions = [[self.names.index(f"isolators[{i}].position.{a}") for a in "xyz"]
                        for i in range(self.n_isolators)]
        touched = [i for row in at_positions for i in row if i in which]
        if touched:
            zero = (0.0, 0.0, 0.0)
            isolators = tuple(Isolator(tuple(float(p[i]) for i in row), zero, zero)  # type: ignore[arg-type]
                              for row in at_positions)
            try:
                check_isolator_layout(isolators)
            except ScenarioError as exc:
                raise ParameterError(f"{key(touched[0])}: {exc}") from None

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
        if self.pneumatic is None:
            take("positions", 3, m)
            take("stiffness", 3, m)
            take("damping", 3, m)
        take("actuator_positions", 3, self.n_actuators)
        take("actuator_directions", 3, self.n_actuators)
        if self.pneumatic is not None:
            out.update(self.pneumatic.unpack(p[i:]))
        sizes = {"axes": n, "origins": n, "actuator_positions": self.n_actuators,
                 "actuator_directions": self.n_actuators}
        for k in ("axes", "origins", "positions", "stiffness", "damping", "actuator_positions",
                  "actuator_directions"):
            if sizes.get(k, m) <= 1 and out[k].shape != (3, sizes.get(k, m)):
                out[k] = ca.reshape(out[k], 3, sizes.get(k, m))
        return out


check_public(globals(), ("ParameterLayout"))
