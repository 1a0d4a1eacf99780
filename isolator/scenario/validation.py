"""Checks of a whole scenario that no single key can make (layout, carriage tree, strokes).

:func:`validate_scenario` is run by the file reader on every scenario it builds, and by the API entry points
that build or change scenarios; each failure is one :class:`ScenarioError` naming the key.
"""

from __future__ import annotations

import math

import numpy as np

from isolator.errors import ScenarioError
from isolator.scenario.definitions import Carriage, Isolator, Scenario
from isolator.scenario.flexible_checks import check_flexible
from isolator.scenario.names import check_names
from isolator.scenario.pneumatic import PneumaticIsolator, group_statics_matrix
from isolator.scenario.rules import check_scenario_values
from isolator.scenario.sequence import StepSequence
from isolator.scenario.windows import check_windows

__all__ = [
    "check_carriage_tree",
    "check_duration",
    "check_extent",
    "check_isolator_layout",
    "check_motion",
    "check_phases",
    "check_pneumatics",
    "check_positions",
    "check_sequence",
    "check_strokes",
    "check_unique_names",
    "isolator_rest_pressures",
    "rest_gauge_pressures",
    "validate_scenario",
]


def check_isolator_layout(isolators: tuple[Isolator, ...] | tuple[PneumaticIsolator, ...]) -> None:
    if len(isolators) < 3:
        raise ScenarioError(f"isolators: need at least three, got {len(isolators)}")
    pts = np.array([iso.position for iso in isolators])
    span = np.linalg.svd(pts - pts.mean(axis=0), compute_uv=False)
    scale = max(float(np.abs(pts).max()), 1e-12)
    if span[1] <= 1e-9 * scale:
        raise ScenarioError("isolators: positions all lie on one line; the table could roll about it")


#: how far beyond the table's box (``table.size``) a position in the table frame may lie, in the table's largest
#: dimension: isolators and actuators under a tall frame, sensors on its legs, points on a tool above the table
#: (a position in mm instead of m lies a thousand times farther, in cm a hundred)
FRAME_MARGIN = 2.0


def check_positions(scenario: Scenario) -> None:
    """Every position in the table frame (isolators, actuators, table sensors, points, carriage origins, random
    forces' points of action) within the table's box grown by :data:`FRAME_MARGIN` of its largest dimension on
    every side, when ``table.size`` is given; else one error naming the key, the table's extent along the axis
    and, when a thousandth of it would lie inside, the likely cause (millimetres)."""
    size = scenario.table.size
    if size is None:
        return
    half = np.asarray(size, dtype=float) / 2.0
    margin = FRAME_MARGIN * float(max(size))
    sensors = [(i, s) for i, s in enumerate(scenario.sensors) if s.on == "table"]
    isolators: list[Isolator | PneumaticIsolator] = list(scenario.isolators)
    groups = [(f"isolators[{i}].position", x.position) for i, x in enumerate(isolators)]
    groups += [(f"actuators[{i}].position", x.position) for i, x in enumerate(scenario.actuators)]
    groups += [(f"sensors[{i}].position", x.position) for i, x in sensors]
    groups += [(f"points[{i}].position", x.position) for i, x in enumerate(scenario.points)]
    groups += [(f"carriages[{i}].origin", x.origin) for i, x in enumerate(scenario.carriages)]
    groups += [(f"disturbances[{i}].position", x.position) for i, x in enumerate(scenario.disturbances)]
    for key, position in groups:
        p = np.asarray(position, dtype=float)
        beyond = np.abs(p) - half - margin
        if np.any(beyond > 0):
            axis = int(np.argmax(beyond))
            shown = ", ".join(f"{v:.4g}" for v in p)
            mm = " (a position in mm? the table frame is in m)" if np.all(np.abs(p) / 1000 <= half + margin) and \
                np.max(np.abs(p)) > 100 * np.max(half) else ""
            raise ScenarioError(
                f"{key}: [{shown}] m lies {beyond[axis]:.4g} m beyond what the table reaches along "
                f"{'xyz'[axis]}: its extent is +-{half[axis]:.4g} m from the mass centre (table.size = "
                f"[{', '.join(f'{v:g}' for v in size)}] m), with {margin:.4g} m for parts under a frame{mm}")


def check_unique_names(names: list[str], section: str) -> None:
    """Each name of a section by the rule for names (:func:`isolator.scenario.names.check_names`), once."""
    check_names(names, section)


def check_carriage_tree(carriages: tuple[Carriage, ...]) -> None:
    names = [c.name for c in carriages]
    check_unique_names(names, "carriages")
    for i, c in enumerate(carriages):
        if c.parent == c.name:
            raise ScenarioError(f"carriages[{i}].parent: a carriage cannot be its own parent")
        if c.parent != "table" and c.parent not in names:
            raise ScenarioError(
                f"carriages[{i}].parent: unknown parent '{c.parent}' (use 'table' or a carriage name)"
            )
    parent = {c.name: c.parent for c in carriages}
    for i, c in enumerate(carriages):
        seen = [c.name]
        p = c.parent
        while p != "table":
            if p in seen:
                chain = " -> ".join([*seen, p])
                raise ScenarioError(f"carriages[{i}].parent: cyclic parents ({chain})")
            seen.append(p)
            p = parent[p]


def check_strokes(scenario: Scenario) -> None:
    """Every carriage's mass must stay above the table's footprint (when its size is known)."""
    if scenario.table.size is None or not scenario.carriages:
        return
    t_end = scenario.simulation.duration
    if math.isfinite(scenario.stop_time):
        t_end = max(t_end, scenario.stop_time)
    times = np.linspace(0.0, t_end, 4001)
    extra = [b for b in scenario.breakpoints if 0.0 <= b <= t_end]
    times = np.union1d(times, extra)
    q = np.array([c.profile.evaluate(times)[0] for c in scenario.carriages])
    excess = scenario.outside_footprint(q)
    if excess is not None:
        i, axis, k, coordinate = excess
        half = scenario.table.size[axis] / 2.0
        which = "half-length" if axis == 0 else "half-width"
        raise ScenarioError(
            f"carriages[{i}].profile: the carriage's mass reaches {'xy'[axis]} = "
            f"{coordinate:.4g} m at t = {times[k]:.4g} s, beyond the table's "
            f"{which} {half:.4g} m (table.size)"
        )


def check_extent(scenario: Scenario) -> None:
    """Everything against ``table.size``: :func:`check_positions`, then :func:`check_strokes`."""
    check_positions(scenario)
    check_strokes(scenario)


def check_sequence(scenario: Scenario) -> None:
    """A ``[sequence]`` against the carriages: every named carriage exists, has full ``limits`` and no
    profile of its own, every per-step limit is at most the carriage's, and every configuration the
    steps reach (and the initial one) keeps every carriage's mass above the table's footprint. The
    S-curves are monotone between configurations and the footprint test is per axis on positions
    affine in ``q``, so the configurations are all the moves can reach."""
    sequence = scenario.sequence
    if sequence is None:
        return
    _check_sequence_numbers(sequence)
    names = [c.name for c in scenario.carriages]
    known = ", ".join(names) if names else "none declared in [[carriages]]"
    for name, _ in sequence.initial:
        if name not in names:
            raise ScenarioError(f"sequence.initial.{name}: unknown carriage '{name}' (carriages: {known})")
    for i, c in enumerate(scenario.carriages):
        if c.profile.stop_time != 0.0 or c.profile.position(0.0) != sequence.initial_positions(names)[i]:
            raise ScenarioError(f"carriages[{i}].profile: with [sequence] the carriages give no profile "
                                "(the sequence's steps move them)")
    for k, step in enumerate(sequence.steps):
        for name, move in step.moves:
            key = f"sequence.steps[{k}].{name}"
            if name not in names:
                raise ScenarioError(f"{key}: unknown carriage '{name}' (carriages: {known})")
            i = names.index(name)
            limits = scenario.carriages[i].limits
            for kind in ("velocity", "acceleration", "jerk"):
                own = getattr(limits, kind)
                if own is None:
                    raise ScenarioError(f"carriages[{i}].limits.{kind}: missing; a carriage a [sequence] moves "
                                        "needs velocity, acceleration and jerk limits (its S-curves)")
                step_value = getattr(move, kind)
                if step_value is not None and step_value > own * (1 + 1e-12):
                    raise ScenarioError(f"{key}.{kind}: {step_value:g} is above the carriage's limit "
                                        f"carriages[{i}].limits.{kind} = {own:g}")
    configurations = sequence.configurations(names)
    excess = scenario.outside_footprint(configurations.T) if names else None
    if excess is not None and scenario.table.size is not None:
        i, axis, k, coordinate = excess
        where = "sequence.initial" if k == 0 else f"sequence.steps[{k - 1}]"
        moved = names[i] if k == 0 or sequence.steps[k - 1].move(names[i]) is not None else None
        key = f"{where}.{moved}" if moved else where
        half = scenario.table.size[axis] / 2.0
        which = "half-length" if axis == 0 else "half-width"
        raise ScenarioError(f"{key}: carriage '{names[i]}''s mass reaches {'xy'[axis]} = {coordinate:.4g} m "
                            f"there, beyond the table's {which} {half:.4g} m (table.size)")


def _check_sequence_numbers(sequence: StepSequence) -> None:
    """The reader's rules for a sequence built from the dataclasses: finite numbers, ``measure``, ``start``
    and delays >= 0, per-step limits > 0, at least one step, each naming a carriage."""
    def check(value: object, key: str, low: float | None = None, strict: bool = False) -> None:
        ok = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
        if not ok or (low is not None and (value <= low if strict else value < low)):  # type: ignore[operator]
            bound = "" if low is None else f" {'>' if strict else '>='} {low:g}"
            raise ScenarioError(f"{key}: must be a finite number{bound}, got {value!r}")

    check(sequence.measure, "sequence.measure", 0.0)
    check(sequence.start, "sequence.start", 0.0)
    for name, q in sequence.initial:
        check(q, f"sequence.initial.{name}")
    if not sequence.steps:
        raise ScenarioError("sequence.steps: is empty; a sequence needs at least one step")
    for k, step in enumerate(sequence.steps):
        if not step.moves:
            raise ScenarioError(f"sequence.steps[{k}]: names no carriage (a step moves at least one)")
        for name, move in step.moves:
            key = f"sequence.steps[{k}].{name}"
            check(move.target, key if move.plain else f"{key}.target")
            check(move.delay, f"{key}.delay", 0.0)
            for kind in ("velocity", "acceleration", "jerk"):
                if getattr(move, kind) is not None:
                    check(getattr(move, kind), f"{key}.{kind}", 0.0, strict=True)


def check_duration(scenario: Scenario) -> None:
    """The run must reach every carriage's start and stop: a run that ends before the motion would
    report a table at rest (settling 0 s) for a move it never simulated."""
    duration = scenario.simulation.duration
    for i, carriage in enumerate(scenario.carriages):
        profile = carriage.profile
        start = float(profile.breakpoints[0]) if profile.breakpoints else 0.0
        stop = float(profile.stop_time)
        if start >= duration and start > 0.0:
            ends = "" if math.isinf(stop) else f" and stops at {stop:.6g} s"
            raise ScenarioError(
                f"simulation.duration: {duration:.6g} s ends before carriages[{i}] ('{carriage.name}') "
                f"starts moving at {start:.6g} s (profile t0){ends}; make simulation.duration longer "
                "than the stop time"
            )
        if math.isfinite(stop) and stop > duration:
            raise ScenarioError(
                f"simulation.duration: {duration:.6g} s ends before carriages[{i}] ('{carriage.name}') "
                f"stops at {stop:.6g} s (stop time); make simulation.duration longer than the stop time "
                "to see the table settle"
            )


#: the shortest profile phase a run resolves, relative to max(1 s, its time): shorter ones are float noise
SHORTEST_PHASE = 1e-12


def check_phases(scenario: Scenario) -> None:
    """Every phase of every carriage's profile that changes the speed long enough for the run to resolve
    (an impulsive move whose pulse would be lost refuses, naming the profile and the shortest phase it
    can have; a phase of rounding length that changes nothing is harmless)."""
    for i, carriage in enumerate(scenario.carriages):
        knots = np.asarray(carriage.profile.breakpoints, dtype=float)
        if knots.size < 2:
            continue
        phases = np.diff(knots)
        limit = SHORTEST_PHASE * np.maximum(1.0, knots[1:])
        mid = 0.5 * (knots[1:] + knots[:-1])
        profile = carriage.profile
        change = np.abs(profile.evaluate(knots[1:], mid)[1] - profile.evaluate(knots[:-1], mid)[1])
        speed = float(np.max(np.abs(profile.evaluate(knots, knots)[1]), initial=0.0))
        short = (phases < limit) & (change > 1e-6 * max(speed, 1e-12)) | (phases < 0)
        if short.any():
            k = int(np.argmax(short))
            raise ScenarioError(
                f"carriages[{i}].profile: a phase of {phases[k]:.3g} s at t = {knots[k]:.6g} s is too short to "
                f"resolve (at least {limit[k]:.3g} s); lower the acceleration or jerk"
            )


def check_motion(scenario: Scenario) -> None:
    """What a run needs of the carriages' motion: :func:`check_duration` and :func:`check_phases`."""
    check_duration(scenario)
    check_phases(scenario)


def rest_gauge_pressures(scenario: Scenario, positions: np.ndarray | None = None) -> np.ndarray:
    """Gauge pressure of each leveling group holding the table level at its rest pose [Pa], (groups,).

    Three equations (vertical force, moments about x and y, table frame at the
    reference pose) in the three group pressures, with the carriages at
    ``positions`` [m] (default: their start).

    Raises
    ------
    ScenarioError
        When the groups' isolators make the statics singular.
    """
    pneumatic = tuple(iso for iso in scenario.isolators if isinstance(iso, PneumaticIsolator))
    matrix = group_statics_matrix(pneumatic, scenario.leveling)
    q = scenario.initial_positions() if positions is None else np.asarray(positions, dtype=float)
    g = scenario.gravity
    load = np.array([g * scenario.total_mass, 0.0, 0.0])
    if scenario.carriages:
        where = scenario.carriage_positions(q)
        masses = np.array([c.mass for c in scenario.carriages])
        load[1:] = g * masses @ where[:, [1, 0]]
    if matrix.shape != (3, 3) or np.linalg.cond(matrix) > 1e12:
        raise ScenarioError(
            "leveling: the groups' isolators make the statics singular (three groups whose isolators "
            "do not all lie on one line are needed to hold the table level)"
        )
    return np.asarray(np.linalg.solve(matrix, load), dtype=float)


def isolator_rest_pressures(scenario: Scenario, positions: np.ndarray | None = None) -> np.ndarray:
    """Each pneumatic isolator's rest gauge pressure, its group's (:func:`rest_gauge_pressures`) [Pa], (isolators,)."""
    groups = rest_gauge_pressures(scenario, positions)
    owner = {k: j for j, g in enumerate(scenario.leveling) for k in g.isolators}
    return np.array([groups[owner[k]] for k in range(len(scenario.isolators))])


def check_pneumatics(scenario: Scenario) -> None:
    """Every group's rest gauge pressure (carriages at their start) within ``(0, supply]``."""
    if not scenario.is_pneumatic:
        return
    pressures = rest_gauge_pressures(scenario)
    for j, (group, p) in enumerate(zip(scenario.leveling, pressures, strict=True)):
        if p <= 0.0:
            raise ScenarioError(
                f"leveling[{j}]: group '{group.name}' would need a gauge pressure of {p:.4g} Pa at rest "
                "(at or below the atmosphere: it cannot pull the table down; move the isolators or the groups)"
            )
        if p > group.supply:
            raise ScenarioError(
                f"leveling[{j}].supply: group '{group.name}' needs a rest gauge pressure of {p:.4g} Pa, "
                f"above its supply {group.supply:.4g} Pa (larger piston areas or a higher supply)"
            )


def validate_scenario(scenario: Scenario) -> Scenario:
    """Run every whole-scenario check on ``scenario`` and return it.

    Raises
    ------
    ScenarioError
        The first check that fails, naming its key.
    """
    check_scenario_values(scenario)
    check_positions(scenario)
    check_isolator_layout(scenario.isolators)
    check_carriage_tree(scenario.carriages)
    check_unique_names([a.name for a in scenario.actuators], "actuators")
    check_unique_names([pt.name for pt in scenario.points], "points")
    check_unique_names([s.name for s in scenario.sensors], "sensors")
    check_windows(scenario.windows, [pt.name for pt in scenario.points])
    check_sequence(scenario)
    check_motion(scenario)
    check_strokes(scenario)
    check_pneumatics(scenario)
    check_flexible(scenario)
    return scenario
