"""What every number of a scenario must be, in one place: the file reader and the parameter vectors check by it.

A rule belongs to a *field*: a scenario key or parameter name without its
indices and components (``isolators[2].damping[1]`` and the parameter
``isolators[2].damping.y`` are both the field ``isolators.damping``). The file
reader (:func:`isolator.scenario.reader.scenario_from_dict`) and
:func:`isolator.scenario.validation.validate_scenario` check a scenario's
numbers by :func:`check_scenario_values`; :class:`isolator.model.parameters.ParameterLayout`
checks parameter vectors (``Simulator.run(changes=..., p=...)``,
``linearise(parameters=...)``) by :func:`check_parameters`. Both raise through
:func:`check_value`, so a rule changed here changes both.

Every failure is one error whose message starts with the key it is given, e.g.
``changes['isolators[0].damping.z']: must be >= 0, got -5``.
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from isolator.errors import IsolatorError, ParameterError, ScenarioError
from isolator.scenario.definitions import Isolator, Scenario
from isolator.scenario.flexible import flexible_values
from isolator.scenario.names import check_scenario_names
from isolator.scenario.pneumatic import PneumaticIsolator
from isolator.scenario.profiles import PiecewisePolynomialProfile, Profile, SineProfile

__all__ = [
    "MAGNITUDE",
    "MOVE_FLOOR",
    "RULES",
    "UNIT_TOLERANCE",
    "Rule",
    "check_arguments",
    "check_parameters",
    "check_scenario_values",
    "check_value",
    "closest",
    "field_of",
    "profile_values",
    "rule_for",
    "scenario_values",
]

#: the largest size of any number of a scenario (SI units); squares of larger ones overflow in the equations
MAGNITUDE = 1e15
#: how far a unit vector's length may be from 1 (the reader normalises within it)
UNIT_TOLERANCE = 1e-6
#: the polytropic exponent's allowed range (isothermal .. a little above diatomic adiabatic)
POLYTROPIC_RANGE = (1.0, 1.67)

_COMPONENTS = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class Rule:
    """What one field's numbers must be (always finite numbers).

    Attributes
    ----------
    low, high : float or None
        Bounds; ``low_open`` / ``high_open``: excluded.
    unit : bool
        The field is a direction: its three components a unit vector.
    triangle : bool
        Principal moments of inertia: each at most the sum of the other two.
    integer : bool
        A count: a whole number.
    """

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    unit: bool = False
    triangle: bool = False
    why: str = ""
    integer: bool = False

    def problem(self, value: float) -> str | None:
        """Why ``value`` breaks the rule (None: it does not)."""
        if not math.isfinite(value):
            return f"must be finite, got {value}"
        if abs(value) > MAGNITUDE:
            return f"must be at most {MAGNITUDE:g} in size (SI units: beyond any table, and the equations overflow), " \
                   f"got {value:g}"
        low, high = self.low, self.high
        if low is not None and high is not None and not (low <= value <= high):
            left, right = "(" if self.low_open else "[", ")" if self.high_open else "]"
            return f"must be in {left}{low:g}, {high:g}{right}, got {value:g}"
        if low is not None and low > 0 and value <= 0:  # the sign first: a floor is for tiny positive values
            return f"must be > 0, got {value:g}"
        if low is not None and (value <= low if self.low_open else value < low):
            return f"must be {'>' if self.low_open else '>='} {low:g}{self.why}, got {value:g}"
        if high is not None and (value >= high if self.high_open else value > high):
            return f"must be {'<' if self.high_open else '<='} {high:g}, got {value:g}"
        return f"must be a whole number, got {value:g}" if self.integer and value != math.floor(value) else None


FINITE = Rule()
POSITIVE = Rule(low=0.0, low_open=True)
NONNEGATIVE = Rule(low=0.0)
#: the least speed, acceleration or jerk of a move (SI units): slower is no stage's move, and the products of
#: smaller ones underflow (a move of acceleration 1e-300 vanished)
MOVE_FLOOR = 1e-9
#: a move's speed, acceleration, jerk: at least MOVE_FLOOR
MOTION = Rule(low=MOVE_FLOOR, why=" (slower than any stage moves: 1 nm/s, 1 nm/s^2, 1 nm/s^3)")

#: the rule of every numeric field of a scenario, by field (keys without indices and components)
RULES: dict[str, Rule] = {
    "gravity": NONNEGATIVE,
    "table.mass": Rule(low=1e-3, why=" kg (lighter than any table; its inertia from table.size would underflow)"),
    "table.inertia": Rule(low=0.0, low_open=True, triangle=True),
    "table.size": POSITIVE,
    "carriages.mass": POSITIVE,
    "carriages.axis": Rule(unit=True),
    "carriages.origin": FINITE,
    "carriages.limits.velocity": MOTION,
    "carriages.limits.acceleration": MOTION,
    "carriages.limits.jerk": MOTION,
    "carriages.profile.start": FINITE,
    "carriages.profile.stroke": FINITE,
    "carriages.profile.velocity": MOTION,
    "carriages.profile.acceleration": MOTION,
    "carriages.profile.deceleration": MOTION,
    "carriages.profile.jerk": MOTION,
    "carriages.profile.deceleration_jerk": MOTION,
    "carriages.profile.t0": NONNEGATIVE,
    "carriages.profile.amplitude": FINITE,
    "carriages.profile.omega": POSITIVE,
    "carriages.profile.phase": FINITE,
    "carriages.profile.offset": FINITE,
    "isolators.position": FINITE,
    "isolators.stiffness": NONNEGATIVE,
    "isolators.damping": NONNEGATIVE,
    "isolators.area": POSITIVE,
    "isolators.volume": POSITIVE,
    "isolators.damping_volume": NONNEGATIVE,
    "isolators.orifice.diameter": POSITIVE,
    "isolators.orifice.length": POSITIVE,
    "isolators.horizontal_stiffness": NONNEGATIVE,
    "isolators.horizontal_damping": NONNEGATIVE,
    "actuators.position": FINITE,
    "actuators.direction": Rule(unit=True),
    "actuators.max_force": POSITIVE,
    "actuators.bandwidth": POSITIVE,
    "actuators.max_rate": POSITIVE,
    "points.position": FINITE,
    "leveling.line.diameter": POSITIVE,
    "leveling.line.length": POSITIVE,
    "leveling.sensor": FINITE,
    "leveling.supply": POSITIVE,
    "leveling.valve.gain": POSITIVE,
    "leveling.valve.deadband": NONNEGATIVE,
    "leveling.valve.max_flow": POSITIVE,
    "air.atmosphere": POSITIVE,
    "air.temperature": POSITIVE,
    "air.gas_constant": POSITIVE,
    "air.viscosity": POSITIVE,
    "air.polytropic": Rule(low=POLYTROPIC_RANGE[0], high=POLYTROPIC_RANGE[1]),
    "simulation.duration": POSITIVE,
    "simulation.sample_rate": POSITIVE,
    "table.flexible.count": Rule(low=1.0, integer=True), "table.flexible.max_frequency": POSITIVE,
    "table.flexible.damping": Rule(low=0.0, high=1.0, high_open=True), "table.flexible.origin": FINITE,
    "points.feet": FINITE, "carriages.feet": FINITE,
}

_INDEX = re.compile(r"\[\d+\]")


@lru_cache(maxsize=4096)
def field_of(name: str) -> str | None:
    """The field of a key or parameter name (``isolators[0].damping.z`` -> ``isolators.damping``), None if unknown."""
    bare = _INDEX.sub("", name)
    if bare in RULES:
        return bare
    head, _, last = bare.rpartition(".")
    if last in _COMPONENTS and head in RULES:
        return head
    return None


def rule_for(name: str) -> Rule | None:
    """The rule of a key or parameter name (None: no rule, e.g. a string)."""
    field = field_of(name)
    return None if field is None else RULES[field]


def check_value(name: str, value: object, key: str | None = None,
                error: type[IsolatorError] = ScenarioError) -> float:
    """``value`` as a float, checked by the rule of ``name``; else ``error`` starting with ``key`` (default ``name``).

    A name without a rule only has to be a finite number.
    """
    key = name if key is None else key
    if isinstance(value, bool | str | bytes):
        raise error(f"{key}: must be a number, got {value!r}")
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise error(f"{key}: must be a number, got {value!r}") from None
    problem = (rule_for(name) or FINITE).problem(x)
    if problem is not None:
        raise error(f"{key}: {problem}")
    return x


def vector_problem(name: str, values: Sequence[float]) -> str | None:
    """Why a whole vector field breaks its rule (a direction not of unit length, inertia not a triangle)."""
    rule = rule_for(name)
    if rule is None:
        return None
    if rule.unit:
        norm = math.sqrt(sum(v * v for v in values))
        if norm == 0.0:
            return "must be a unit vector, got zero length"
        if abs(norm - 1.0) > UNIT_TOLERANCE:
            return f"must be a unit vector, got length {norm:.6g}"
    if rule.triangle:
        a, b, c = values
        if a + b < c * (1 - 1e-9) or a + c < b * (1 - 1e-9) or b + c < a * (1 - 1e-9):
            return ("principal moments must satisfy the triangle inequality "
                    f"(each <= the sum of the other two), got {[float(v) for v in values]}")
    return None


def closest(name: str, names: Sequence[str]) -> str | None:
    """The valid name most like ``name`` (difflib), None if none is close."""
    match = difflib.get_close_matches(name, list(names), n=1, cutoff=0.6)
    return match[0] if match else None


def check_parameters(
    names: Sequence[str],
    values: Sequence[float] | np.ndarray,
    key: Callable[[int], str],
    error: type[IsolatorError],
    entries: Sequence[int] | None = None,
    vector_key: Callable[[list[int], str], str] | None = None,
) -> None:
    """Check named parameter values by :data:`RULES`, entry by entry and as vectors.

    Parameters
    ----------
    names : sequence of str
        Parameter names (``ParameterLayout.names``), components as ``.x, .y, .z``.
    values : sequence of float
    key : callable
        The key an error about entry ``i`` starts with.
    error : IsolatorError subclass
        ``ParameterError`` for arguments, ``ScenarioError`` for scenario content.
    entries : sequence of int, optional
        Only these entries (and the vectors they are part of); default all.
    vector_key : callable, optional
        The key an error about a whole vector (its entries, its name) starts with; default: ``key`` of the
        first entry given, then the vector's name.
    """
    which = range(len(names)) if entries is None else sorted(set(entries))
    chosen = set(which)
    for i in which:
        check_value(names[i], values[i], key(i), error)
    vectors: dict[str, list[int]] = {}
    for i, name in enumerate(names):
        head, _, last = name.rpartition(".")
        rule = rule_for(name)
        if last in _COMPONENTS and rule is not None and (rule.unit or rule.triangle):
            vectors.setdefault(head, []).append(i)
    for head, members in vectors.items():
        touched = [i for i in members if i in chosen]
        if not touched or len(members) != 3:
            continue
        problem = vector_problem(head, [float(values[i]) for i in members])
        if problem is not None:
            raise error(f"{vector_key(members, head)}: {problem}" if vector_key is not None
                        else f"{key(touched[0])}: {head} {problem}")


def _vector(key: str, values: Any) -> Iterator[tuple[str, object]]:
    if isinstance(values, str | bytes) or not hasattr(values, "__len__") or not hasattr(values, "__getitem__"):
        raise ScenarioError(f"{key}: must be a list of numbers, got {values!r}")
    for i, v in enumerate(values):
        yield f"{key}[{i}]", v


def profile_values(profile: Profile, key: str) -> Iterator[tuple[str, object]]:
    """A profile's numbers (a sine's fields, a trapezoid's or S-curve's keys) by their file keys."""
    if isinstance(profile, SineProfile):
        for name in ("amplitude", "omega", "phase", "offset", "t0"):
            yield f"{key}.{name}", getattr(profile, name)
    elif isinstance(profile, PiecewisePolynomialProfile):
        for name, value in profile.spec:
            yield f"{key}.{name}", value


def check_arguments(error: type[IsolatorError] = ParameterError, /, **values: object) -> None:
    """Arguments of a profile builder by the rules of the profile keys they are (``velocity``, ``t0``, ...)."""
    for name, value in values.items():
        check_value(f"carriages.profile.{name}", value, name, error)


def scenario_values(scenario: Scenario) -> Iterator[tuple[str, object]]:
    """Every number of a scenario with its file key (``isolators[0].damping[2]``), vectors one component each."""
    yield "gravity", scenario.gravity
    yield "table.mass", scenario.table.mass
    yield from _vector("table.inertia", scenario.table.inertia)
    if scenario.table.size is not None:
        yield from _vector("table.size", scenario.table.size)
    yield "simulation.duration", scenario.simulation.duration
    yield "simulation.sample_rate", scenario.simulation.sample_rate
    isolators: tuple[Isolator | PneumaticIsolator, ...] = scenario.isolators
    for i, iso in enumerate(isolators):
        k = f"isolators[{i}]"
        yield from _vector(f"{k}.position", iso.position)
        if isinstance(iso, Isolator):
            yield from _vector(f"{k}.stiffness", iso.stiffness)
            yield from _vector(f"{k}.damping", iso.damping)
        elif isinstance(iso, PneumaticIsolator):
            yield f"{k}.area", iso.area
            yield f"{k}.volume", iso.volume
            yield f"{k}.damping_volume", iso.damping_volume
            if iso.orifice is not None:
                yield f"{k}.orifice.diameter", iso.orifice.diameter
                yield f"{k}.orifice.length", iso.orifice.length
            yield from _vector(f"{k}.horizontal_stiffness", iso.horizontal_stiffness)
            yield from _vector(f"{k}.horizontal_damping", iso.horizontal_damping)
    for i, c in enumerate(scenario.carriages):
        k = f"carriages[{i}]"
        yield f"{k}.mass", c.mass
        yield from _vector(f"{k}.axis", c.axis)
        yield from _vector(f"{k}.origin", c.origin)
        for name in ("velocity", "acceleration", "jerk"):
            if getattr(c.limits, name, None) is not None:
                yield f"{k}.limits.{name}", getattr(c.limits, name)
        yield from profile_values(c.profile, f"{k}.profile")
    for i, a in enumerate(scenario.actuators):
        k = f"actuators[{i}]"
        yield from _vector(f"{k}.position", a.position)
        yield from _vector(f"{k}.direction", a.direction)
        yield f"{k}.max_force", a.max_force
        if a.bandwidth is not None:
            yield f"{k}.bandwidth", a.bandwidth
        if a.max_rate is not None:
            yield f"{k}.max_rate", a.max_rate
    for i, pt in enumerate(scenario.points):
        yield from _vector(f"points[{i}].position", pt.position)
    for j, g in enumerate(scenario.leveling):
        k = f"leveling[{j}]"
        if g.line is not None:
            yield f"{k}.line.diameter", g.line.diameter
            yield f"{k}.line.length", g.line.length
        yield from _vector(f"{k}.sensor", g.sensor)
        yield f"{k}.supply", g.supply
        if g.valve is not None:
            yield f"{k}.valve.gain", g.valve.gain
            yield f"{k}.valve.deadband", g.valve.deadband
            yield f"{k}.valve.max_flow", g.valve.max_flow
    if scenario.air is not None:
        for name in ("atmosphere", "temperature", "gas_constant", "viscosity", "polytropic"):
            yield f"air.{name}", getattr(scenario.air, name)
    yield from flexible_values(scenario.table.flexible, scenario.points, scenario.carriages)


_VECTOR_LENGTHS = {"table.inertia": 3, "table.size": 3, "carriages.axis": 3, "carriages.origin": 3,
                   "isolators.position": 3, "isolators.stiffness": 3, "isolators.damping": 3,
                   "actuators.position": 3, "actuators.direction": 3, "points.position": 3,
                   "isolators.horizontal_stiffness": 2, "isolators.horizontal_damping": 2, "leveling.sensor": 2,
                   "table.flexible.origin": 3, "points.feet": 2, "carriages.feet": 2}


def check_scenario_values(scenario: Scenario) -> None:
    """Every name (:func:`check_scenario_names`) and number (by :data:`RULES`) of a scenario, however it was built;
    one :class:`ScenarioError` naming the key.

    For scenarios built from the dataclasses directly: the file reader checks the same rules key by key.
    """
    check_scenario_names(scenario)
    vectors: dict[str, list[float]] = {}
    for key, value in scenario_values(scenario):
        x = check_value(key, value)
        head, bracket, _ = key.rpartition("[")
        if bracket and key.endswith("]") and field_of(head) in _VECTOR_LENGTHS:
            vectors.setdefault(head, []).append(x)
    for head, values in vectors.items():
        field = field_of(head)
        if field is not None and len(values) != _VECTOR_LENGTHS[field]:
            raise ScenarioError(f"{head}: must be a list of {_VECTOR_LENGTHS[field]} numbers, got {len(values)}")
        problem = vector_problem(head, values)
        if problem is not None:
            raise ScenarioError(f"{head}: {problem}")

