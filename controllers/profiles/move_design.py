"""Carriage moves as a few design parameters: what a profile optimiser changes.

A rest-to-rest move of fixed start and stroke is a trapezoid (acceleration,
deceleration, cruise speed, start delay) or a seven-segment S-curve (the same
plus jerk). :class:`MoveDesign` holds one carriage's parameters and limits,
builds its profile, and writes its segments as functions of the parameters
(numbers or casadi expressions), so the same formulas serve the optimiser's
symbolic model and the checks. Durations stay smooth in the parameters as long
as every segment is at least zero long, which the optimiser imposes.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import casadi as ca
import numpy as np

from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Carriage, Scenario
from isolator.scenario.profile_shapes import scurve, trapezoid
from isolator.scenario.profiles import PiecewisePolynomialProfile
from isolator.scenario.rules import check_arguments, check_value

__all__ = [
    "DEFAULT_JERK_RAMP",
    "SHAPES",
    "DriveLimits",
    "MoveDesign",
    "Segment",
    "command_time",
    "move_designs",
    "move_time",
]

#: profile shapes the optimiser designs
SHAPES = ("trapezoid", "scurve")

#: when neither the carriage's ``limits.jerk`` nor its S-curve gives a jerk
#: limit: the time [s] the largest acceleration takes to build up
DEFAULT_JERK_RAMP = 0.05


@dataclass(frozen=True)
class DriveLimits:
    """A carriage drive's limits, all given (see :func:`drive_limits`).

    Attributes
    ----------
    velocity : float
        [m/s]
    acceleration : float
        Acceleration and deceleration [m/s^2].
    jerk : float
        [m/s^3]
    """

    velocity: float
    acceleration: float
    jerk: float

    def __post_init__(self) -> None:
        for name in ("velocity", "acceleration", "jerk"):
            check_value(f"carriages.limits.{name}", getattr(self, name), f"limits.{name}", ParameterError)


def drive_limits(carriage: Carriage, index: int) -> DriveLimits:
    """The carriage's ``limits`` with the gaps filled from its own profile.

    Speed and acceleration default to the profile's (the larger of its
    acceleration and deceleration); jerk to an S-curve's jerk, otherwise to the
    largest acceleration over :data:`DEFAULT_JERK_RAMP`.
    """
    spec = _spec(carriage, index)
    acc = max(spec["acceleration"], spec.get("deceleration", 0.0))
    given = carriage.limits
    velocity = given.velocity if given.velocity is not None else spec["velocity"]
    acceleration = given.acceleration if given.acceleration is not None else acc
    if given.jerk is not None:
        jerk = given.jerk
    elif "jerk" in spec:
        jerk = spec["jerk"]
    else:
        jerk = acceleration / DEFAULT_JERK_RAMP
    return DriveLimits(float(velocity), float(acceleration), float(jerk))


def _spec(carriage: Carriage, index: int) -> dict[str, float]:
    profile = carriage.profile
    if not (isinstance(profile, PiecewisePolynomialProfile) and profile.kind in SHAPES and profile.spec):
        raise ScenarioError(
            f"carriages[{index}].profile: profile design needs a trapezoid or an scurve, "
            f"got '{getattr(profile, 'kind', type(profile).__name__)}'"
        )
    return dict(profile.spec)


@dataclass(frozen=True)
class Segment:
    """One constant-jerk piece of a move, its quantities numbers or casadi expressions.

    Attributes
    ----------
    duration : [s]
    acceleration : acceleration at its start [m/s^2]
    jerk : [m/s^3]
    """

    duration: Any
    acceleration: Any
    jerk: Any

    def __post_init__(self) -> None:
        for name in ("duration", "acceleration", "jerk"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, numbers.Real | ca.SX | ca.MX | ca.DM):
                raise ParameterError(f"{name}: must be a number or a casadi expression, got {type(value).__name__}")


@dataclass(frozen=True)
class MoveDesign:
    """One carriage's move as design parameters.

    Attributes
    ----------
    name : str
        The carriage.
    shape : {"trapezoid", "scurve"}
    start, stroke : float
        Fixed [m].
    t0, velocity, acceleration, deceleration : float
        Start time [s], cruise speed [m/s], acceleration and deceleration [m/s^2].
    jerk, deceleration_jerk : float or None
        Jerk of the accelerating and of the braking phase [m/s^3], for an S-curve.
    limits : DriveLimits
    """

    name: str
    shape: str
    start: float
    stroke: float
    t0: float
    velocity: float
    acceleration: float
    deceleration: float
    jerk: float | None
    limits: DriveLimits
    deceleration_jerk: float | None = None

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ParameterError(f"shape: must be one of {', '.join(SHAPES)}, got {self.shape!r}")
        if self.shape == "scurve" and self.jerk is None:
            raise ParameterError("jerk: an scurve needs one, got None")
        if not isinstance(self.limits, DriveLimits):
            raise ParameterError(f"limits: must be DriveLimits, got {type(self.limits).__name__}")
        check_value("t0", self.t0, "t0", ParameterError)  # the optimiser may leave it a hair below 0
        jerks = {"jerk": self.jerk} if self.shape == "scurve" else {}
        if self.shape == "scurve" and self.deceleration_jerk is not None:
            jerks["deceleration_jerk"] = self.deceleration_jerk
        check_arguments(start=self.start, stroke=self.stroke, velocity=self.velocity,
                        acceleration=self.acceleration, deceleration=self.deceleration, **jerks)

    # -- the parameter vector -----------------------------------------------------
    @property
    def names(self) -> tuple[str, ...]:
        """Names of the design parameters, in :attr:`values` order."""
        base = ("t0", "velocity", "acceleration", "deceleration")
        return (*base, "jerk", "deceleration_jerk") if self.shape == "scurve" else base

    @property
    def values(self) -> np.ndarray:
        """The design parameters [s, m/s, m/s^2, m/s^2(, m/s^3, m/s^3)]."""
        return np.array([getattr(self, n) for n in self.names], dtype=float)

    @property
    def scales(self) -> np.ndarray:
        """Typical sizes of the parameters: 1 s and the limits."""
        lim = self.limits
        base = [1.0, lim.velocity, lim.acceleration, lim.acceleration]
        return np.array([*base, lim.jerk, lim.jerk] if self.shape == "scurve" else base)

    @property
    def upper(self) -> np.ndarray:
        """Upper bounds of the parameters (the start time has none)."""
        s = self.scales
        s[0] = math.inf
        return s

    def with_values(self, values: Sequence[float] | np.ndarray) -> MoveDesign:
        """The same move with new parameter values (in :attr:`names` order)."""
        changes: dict[str, Any] = {n: float(v) for n, v in zip(self.names, values, strict=True)}
        return replace(self, **changes)

    # -- geometry -------------------------------------------------------------------
    def segments(self, values: Sequence[Any] | None = None) -> list[Segment]:
        """The move's constant-jerk segments for parameter ``values`` (default: this design's).

        Works on numbers and on casadi expressions alike. A segment of negative
        duration means the parameters do not fit the stroke.
        """
        _, v, a, d, *rest = self.values if values is None else values
        s = 1.0 if self.stroke >= 0 else -1.0
        dist = abs(self.stroke)
        if self.shape == "trapezoid":
            cruise = dist / v - v / (2 * a) - v / (2 * d)
            return [Segment(v / a, s * a, 0.0), Segment(cruise, 0.0, 0.0), Segment(v / d, -s * d, 0.0)]
        j, j_down = rest
        ja, jd = a / j, d / j_down
        cruise = dist / v - (v / a + ja) / 2 - (v / d + jd) / 2
        return [
            Segment(ja, 0.0, s * j), Segment(v / a - ja, s * a, 0.0), Segment(ja, s * a, -s * j),
            Segment(cruise, 0.0, 0.0),
            Segment(jd, 0.0, -s * j_down), Segment(v / d - jd, -s * d, 0.0), Segment(jd, -s * d, s * j_down),
        ]

    def stop_time(self, values: Sequence[Any] | None = None) -> Any:
        """When the carriage comes to rest [s]."""
        t0 = (self.values if values is None else values)[0]
        return t0 + sum(seg.duration for seg in self.segments(values))

    def profile(self) -> PiecewisePolynomialProfile:
        """The profile these parameters make (a trapezoid or an scurve, with its keys)."""
        t0 = max(self.t0, 0.0) if self.t0 > -1e-9 else self.t0  # within the optimiser's bound tolerance
        common = {"start": self.start, "stroke": self.stroke, "velocity": self.velocity,
                  "acceleration": self.acceleration, "deceleration": self.deceleration, "t0": t0}
        if self.shape == "trapezoid":
            return trapezoid(**common)
        return scurve(jerk=float(self.jerk or 0.0), deceleration_jerk=self.deceleration_jerk, **common)

    def fits(self, tolerance: float = 1e-9) -> bool:
        """Every segment at least zero long and every parameter within its limit."""
        lengths = [seg.duration for seg in self.segments()]
        scale = max(1.0, self.stop_time())
        within = np.all(self.values[1:] <= self.upper[1:] * (1 + tolerance))
        return bool(min(lengths) >= -tolerance * scale and within)


def move_designs(scenario: Scenario, shape: str | None = None) -> tuple[MoveDesign, ...]:
    """Each carriage's move as design parameters, starting from its scenario profile.

    Parameters
    ----------
    scenario : Scenario
        Every carriage must move with a trapezoid or an scurve.
    shape : {"trapezoid", "scurve"}, optional
        The shape to design (default: each carriage's own). A trapezoid turned
        into an S-curve takes the jerk limit; its segments are shortened where
        needed so it still fits the stroke.

    Returns
    -------
    tuple of MoveDesign
        One per carriage, in the scenario's order: start, stroke, limits, start delay and shape of its move.

    Raises
    ------
    ScenarioError
        No carriages, a carriage that is not a trapezoid or an scurve.
    ParameterError
        An unknown shape.
    """
    if shape is not None and shape not in SHAPES:
        raise ParameterError(f"shape: must be one of {', '.join(SHAPES)}, got '{shape}'")
    if not scenario.carriages:
        raise ScenarioError("carriages: profile design needs at least one carriage")
    designs = []
    for i, carriage in enumerate(scenario.carriages):
        spec = _spec(carriage, i)
        if spec["stroke"] == 0.0:
            raise ScenarioError(f"carriages[{i}].profile.stroke: profile design needs a move, got a stroke of 0")
        limits = drive_limits(carriage, i)
        kind = shape or carriage.profile.kind  # type: ignore[attr-defined]
        move = MoveDesign(
            name=carriage.name, shape=kind, start=spec["start"], stroke=spec["stroke"], t0=spec.get("t0", 0.0),
            velocity=spec["velocity"], acceleration=spec["acceleration"],
            deceleration=spec.get("deceleration", spec["acceleration"]),
            jerk=(spec.get("jerk", limits.jerk) if kind == "scurve" else None), limits=limits,
            deceleration_jerk=(spec.get("deceleration_jerk", spec.get("jerk", limits.jerk)) if kind == "scurve"
                               else None),
        )
        designs.append(_fitted(move))
    return tuple(designs)


def _fitted(move: MoveDesign) -> MoveDesign:
    """The design with the speed and accelerations its profile really reaches.

    A short stroke never reaches the cruise speed (and an S-curve perhaps not
    its acceleration); the parameters then describe the move that is made, so
    that every segment is at least zero long.
    """
    profile = move.profile()
    t = np.union1d(np.linspace(profile.knots[0], profile.knots[-1], 4001), profile.knots)
    _, v, a = profile.evaluate(t)
    s = 1.0 if move.stroke >= 0 else -1.0
    return replace(
        move, velocity=float(np.max(s * v)), acceleration=float(np.max(s * a)), deceleration=float(np.max(-s * a))
    )


def command_time(scenario: Scenario) -> float:
    """When the scenario's move is commanded [s]: its first carriage start.

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).

    Returns
    -------
    float
        The earliest carriage start [s].

    Examples
    --------
    >>> from isolator import load_scenario
    >>> from controllers.profiles import command_time, move_time
    >>> scenario = load_scenario("paper-table-3-2")
    >>> command_time(scenario), round(move_time(scenario), 3)
    (0.5, 7.4)
    """
    return min(c.profile.knots[0] for c in scenario.carriages)  # type: ignore[attr-defined]


def move_time(scenario: Scenario, command: float | None = None) -> float:
    """Time [s] from the move's command to the last carriage's stop.

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).
    command : float, optional
        When the move is commanded [s] (default: the earliest carriage start).

    Returns
    -------
    float
        The move time [s], from ``command`` to the last carriage's stop.
    """
    begin = command_time(scenario) if command is None else command
    return float(scenario.stop_time - begin)


check_public(globals())
