"""Step-and-settle sequences (``[sequence]``, ``docs/scenario-format.md``): the dataclasses, their reader,
their writer (the ``[sequence]`` table back from a :class:`StepSequence`) and the serpentine raster that
``--pattern`` builds.

A step names, per carriage, a target [m]: a number (the seven-segment S-curve at the carriage's
``limits``), or an inline table ``{ target, velocity, acceleration, jerk, delay }`` whose optional
``velocity``, ``acceleration``, ``jerk`` lower that step's S-curve limits, whose ``delay`` [s] starts
that carriage that long after the step's start, and whose ``shaper = { kind, frequency, damping }`` (or a
list of them) convolves the S-curve with input shapers (:mod:`isolator.scenario.shapers`). What needs the carriages
(known names, limits, the table's footprint) is checked by :func:`isolator.scenario.validation.check_sequence`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.keys import KeyReader, number
from isolator.scenario.profiles import PiecewisePolynomialProfile
from isolator.scenario.shapers import SHAPERS, Shaper, shaper

__all__ = [
    "MOVE_LIMITS",
    "Move",
    "Step",
    "StepSequence",
    "held",
    "parse_pattern",
    "raster_steps",
    "read_sequence",
    "sequence_table",
    "sequence_toml",
]

#: the per-step S-curve limits a step's inline table may lower
MOVE_LIMITS = ("velocity", "acceleration", "jerk")


@dataclass(frozen=True)
class Move:
    """One carriage's move in a step.

    Attributes
    ----------
    target : float
        Where the carriage goes [m] (its coordinate ``q``).
    velocity, acceleration, jerk : float or None
        This move's S-curve limits [m/s], [m/s^2], [m/s^3], each at most the carriage's ``limits``;
        None: the carriage's.
    delay : float
        The carriage starts this long after the step's start [s], >= 0.
    shapers : tuple of Shaper
        Input shapers the S-curve is convolved with, one after the other (each for a mode; the move then
        lasts the shapers' durations longer); empty: none.
    """

    target: float
    velocity: float | None = None
    acceleration: float | None = None
    jerk: float | None = None
    delay: float = 0.0
    shapers: tuple[Shaper, ...] = ()

    def __post_init__(self) -> None:
        if isinstance(self.shapers, Shaper):  # one shaper given where the tuple goes
            object.__setattr__(self, "shapers", (self.shapers,))
        if not isinstance(self.shapers, tuple) or not all(isinstance(t, Shaper) for t in self.shapers):
            raise ScenarioError(f"shapers: must be Shaper objects (isolator.scenario.shapers.shaper), got "
                                f"{self.shapers!r}")

    @property
    def plain(self) -> bool:
        """Whether the move is just a target (written back as a number)."""
        return (self.velocity is None and self.acceleration is None and self.jerk is None and self.delay == 0.0
                and not self.shapers)

    def limits(self, velocity: float, acceleration: float, jerk: float) -> tuple[float, float, float]:
        """This move's S-curve limits: its own where given, else the carriage's (the arguments)."""
        return (velocity if self.velocity is None else self.velocity,
                acceleration if self.acceleration is None else self.acceleration,
                jerk if self.jerk is None else self.jerk)


@dataclass(frozen=True)
class Step:
    """One step: the carriages it moves, in file order (a carriage not named stays put).

    Attributes
    ----------
    moves : tuple of (str, Move)
        Carriage name and its move.
    """

    moves: tuple[tuple[str, Move], ...]

    @property
    def targets(self) -> dict[str, float]:
        """Target per named carriage [m]."""
        return {name: move.target for name, move in self.moves}

    def move(self, name: str) -> Move | None:
        """The move of carriage ``name``; None when the step does not name it."""
        return dict(self.moves).get(name)


@dataclass(frozen=True)
class StepSequence:
    """A step-and-settle sequence.

    Attributes
    ----------
    measure : float
        How long every window must hold before the next step [s], >= 0.
    steps : tuple of Step
        At least one.
    start : float
        When the first step starts [s], >= 0.
    initial : tuple of (str, float)
        Where carriages start [m]; a carriage not named starts at q = 0.
    """

    measure: float
    steps: tuple[Step, ...]
    start: float = 0.0
    initial: tuple[tuple[str, float], ...] = ()

    def initial_positions(self, names: Sequence[str]) -> np.ndarray:
        """The carriages' coordinates before the first step [m], in the order of ``names``."""
        given = dict(self.initial)
        return np.array([given.get(n, 0.0) for n in names], dtype=float)

    def configurations(self, names: Sequence[str]) -> np.ndarray:
        """The carriages' coordinates [m] before the first step and after each step, (steps + 1, carriages)."""
        q = self.initial_positions(names)
        out = [q.copy()]
        index = {n: i for i, n in enumerate(names)}
        for step in self.steps:
            for name, move in step.moves:
                q[index[name]] = move.target
            out.append(q.copy())
        return np.array(out, dtype=float).reshape(len(out), len(names))


def held(q: float) -> PiecewisePolynomialProfile:
    """A carriage at rest at ``q`` [m] for good (the profile of a carriage a ``[sequence]`` moves)."""
    return PiecewisePolynomialProfile((0.0, 0.0), ((float(q), 0.0, 0.0, 0.0),), kind="hold")


# -- reading -------------------------------------------------------------------------------------------------


def read_sequence(top: KeyReader) -> StepSequence | None:
    """The ``[sequence]`` table of a scenario's top level (None without one); the carriage names, limits
    and footprint are checked later (:func:`~isolator.scenario.validation.check_sequence`)."""
    raw = top.raw("sequence", None)  # a misspelt [sequnce] is named here, before the carriages miss profiles
    if raw is None:
        return None
    r = KeyReader(raw, "sequence")
    measure = r.number("measure", nonnegative=True)
    start = r.number("start", 0.0, nonnegative=True)
    initial_raw = r.raw("initial", {})
    if not isinstance(initial_raw, Mapping):
        raise ScenarioError(f"{r.key('initial')}: must be a table of carriage = position [m]")
    initial = tuple((str(name), number(value, f"{r.key('initial')}.{name}")) for name, value in initial_raw.items())
    steps_raw = r.raw("steps")
    if not isinstance(steps_raw, list):
        raise ScenarioError(f"{r.key('steps')}: must be a list of tables, one per step "
                            '(e.g. [{ "x-stage" = 0.1 }, { "x-stage" = 0.2 }])')
    if not steps_raw:
        raise ScenarioError(f"{r.key('steps')}: is empty; a sequence needs at least one step")
    steps = tuple(_read_step(item, f"{r.key('steps')}[{i}]") for i, item in enumerate(steps_raw))
    r.finish()
    return StepSequence(measure=measure, steps=steps, start=start, initial=initial)


def _read_step(item: Any, key: str) -> Step:
    if not isinstance(item, Mapping):
        raise ScenarioError(f"{key}: must be a table of carriage = target [m]")
    if not item:
        raise ScenarioError(f"{key}: names no carriage (a step moves at least one)")
    moves = []
    for name, value in item.items():
        where = f"{key}.{name}"
        if isinstance(value, Mapping):
            moves.append((str(name), _read_move(KeyReader(value, where))))
        else:
            moves.append((str(name), Move(target=number(value, where))))
    return Step(tuple(moves))


def _read_move(r: KeyReader) -> Move:
    target = r.number("target")
    limits = {k: r.number(k, positive=True) if r.has(k) else None for k in MOVE_LIMITS}
    r.used.update(MOVE_LIMITS)
    delay = r.number("delay", 0.0, nonnegative=True)
    trains = _read_shapers(r.key("shaper"), r.raw("shaper")) if r.has("shaper") else ()
    r.finish()
    return Move(target=target, delay=delay, shapers=trains, **limits)


def _read_shapers(key: str, raw: Any) -> tuple[Shaper, ...]:
    """``shaper``: one table or a list of them (convolved, one per mode)."""
    if isinstance(raw, list):
        if not raw:
            raise ScenarioError(f"{key}: an empty list; give one shaper table or leave the key out")
        return tuple(_read_shaper(f"{key}[{i}]", item) for i, item in enumerate(raw))
    return (_read_shaper(key, raw),)


def _read_shaper(key: str, raw: Any) -> Shaper:
    """``shaper = { kind = "zvd", frequency = 3.4, damping = 0.1 }``: a ZV, ZVD or EI shaper of a mode of
    this undamped frequency [Hz] and damping ratio."""
    if not isinstance(raw, Mapping):
        raise ScenarioError(f"{key}: must be a table {{ kind = \"zvd\", frequency = HZ, damping = RATIO }} or a list "
                            "of them")
    r = KeyReader(raw, key)
    kind = r.string("kind")
    if kind not in SHAPERS:
        raise ScenarioError(f"{r.key('kind')}: must be one of {', '.join(SHAPERS)}, got '{kind}'")
    frequency = r.number("frequency", positive=True)
    damping = r.number("damping", 0.0, nonnegative=True)
    if damping >= 1.0:
        raise ScenarioError(f"{r.key('damping')}: must be below 1 (a damping ratio), got {damping}")
    r.finish()
    return shaper(kind, frequency, damping)


# -- writing -------------------------------------------------------------------------------------------------


def sequence_table(sequence: StepSequence) -> dict[str, Any]:
    """The ``[sequence]`` table of ``sequence`` as the reader takes it (a plain move as its target, one
    with per-step limits or a delay as an inline table)."""
    steps = [{name: move.target if move.plain else _move_table(move) for name, move in step.moves}
             for step in sequence.steps]
    table: dict[str, Any] = {"measure": float(sequence.measure)}
    if sequence.start:
        table["start"] = float(sequence.start)
    if sequence.initial:
        table["initial"] = {name: float(q) for name, q in sequence.initial}
    table["steps"] = steps
    return table


def _move_table(move: Move) -> dict[str, Any]:
    out: dict[str, Any] = {"target": float(move.target)}
    for k in MOVE_LIMITS:
        value = getattr(move, k)
        if value is not None:
            out[k] = float(value)
    if move.delay:
        out["delay"] = float(move.delay)
    if move.shapers:
        tables = [{"kind": sh.kind, "frequency": float(sh.frequency), "damping": float(sh.damping)}
                  for sh in move.shapers]
        out["shaper"] = tables[0] if len(tables) == 1 else tables
    return out


def sequence_toml(sequence: StepSequence) -> str:
    """The ``[sequence]`` section of a scenario file for ``sequence`` (TOML text, numbers to 17 digits so
    that reading it back gives the same values)."""
    table = sequence_table(sequence)
    lines = ["[sequence]", f"measure = {_number(table['measure'])}"]
    if "start" in table:
        lines.append(f"start = {_number(table['start'])}")
    if "initial" in table:
        lines.append(f"initial = {_inline(table['initial'])}")
    lines.append("steps = [")
    lines += [f"  {_inline(step)}," for step in table["steps"]]
    lines.append("]")
    return "\n".join(lines) + "\n"


def _number(value: float) -> str:
    return repr(float(value))


def _inline(table: Mapping[str, Any]) -> str:
    items = []
    for key, value in table.items():
        text = _value(value)
        bare = key.replace("-", "").replace("_", "").isalnum() and key.isascii()
        items.append(f"{key if bare else _quoted(key)} = {text}")
    return "{ " + ", ".join(items) + " }"


def _value(value: Any) -> str:
    if isinstance(value, Mapping):
        return _inline(value)
    if isinstance(value, list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    return _quoted(value) if isinstance(value, str) else _number(value)


def _quoted(key: str) -> str:
    return '"' + key.replace("\\", "\\\\").replace('"', '\\"') + '"'


# -- raster patterns -----------------------------------------------------------------------------------------


def parse_pattern(text: str, option: str = "--pattern") -> tuple[str, np.ndarray]:
    """A pattern ``NAME=START:STOP:COUNT`` as the carriage name and its ``COUNT`` positions [m] from
    ``START`` to ``STOP`` inclusive (like ``numpy.linspace``); a :class:`ParameterError` naming ``option``."""
    name, sep, spec = text.partition("=")
    parts = spec.split(":")
    usage = f"{option}: expected NAME=START:STOP:COUNT (metres, metres, a whole number >= 1), got '{text}'"
    if not sep or not name.strip() or len(parts) != 3:
        raise ParameterError(usage)
    try:
        start, stop, count_f = (float(p) for p in parts)
    except ValueError:
        raise ParameterError(usage) from None
    if not (math.isfinite(start) and math.isfinite(stop) and math.isfinite(count_f)) or count_f < 1 \
            or count_f != int(count_f):
        raise ParameterError(usage)
    count = int(count_f)
    if count == 1 and start != stop:
        raise ParameterError(f"{option}: COUNT 1 needs START = STOP, got '{text}'")
    return name.strip(), np.linspace(start, stop, count)


def raster_steps(patterns: Sequence[str | tuple[str, Sequence[float]]]) -> tuple[Step, ...]:
    """The steps of a serpentine raster over a grid.

    Parameters
    ----------
    patterns : sequence
        One or two patterns, ``"x-stage=0:0.3:7"`` (:func:`parse_pattern`) or ``(name, positions)``.
        The first named carriage sweeps along a row, reversing direction every row; the second steps
        once per row (with one pattern, the grid is that row).

    Returns
    -------
    tuple of Step
        One step per grid point, in serpentine order. The first step goes to the first grid point (from
        the sequence's ``initial`` positions) and names every patterned carriage; later steps name only
        the carriages that move.

    Raises
    ------
    ParameterError
        A bad pattern, none, more than two, or a carriage named twice.
    """
    parsed = [parse_pattern(p) if isinstance(p, str) else (p[0], np.asarray(p[1], dtype=float).ravel())
              for p in patterns]
    if not parsed or len(parsed) > 2:
        raise ParameterError(f"--pattern: give one or two patterns (a row, then rows), got {len(parsed)}")
    if len(parsed) == 2 and parsed[0][0] == parsed[1][0]:
        raise ParameterError(f"--pattern: '{parsed[0][0]}' is patterned twice")
    for name, values in parsed:
        if values.size == 0 or not np.all(np.isfinite(values)):
            raise ParameterError(f"--pattern: '{name}' needs at least one finite position")
    fast_name, fast = parsed[0]
    slow_name, slow = parsed[1] if len(parsed) == 2 else ("", np.zeros(1))
    steps: list[Step] = []
    for row, y in enumerate(slow):
        xs = fast if row % 2 == 0 else fast[::-1]
        for col, x in enumerate(xs):
            moves = []
            if not steps or col > 0:  # a new row starts where the last one ended: only the slow carriage moves
                moves.append((fast_name, Move(float(x))))
            if slow_name and (not steps or col == 0):
                moves.append((slow_name, Move(float(y))))
            steps.append(Step(tuple(moves)))
    return tuple(steps)
