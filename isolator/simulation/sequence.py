"""Step-and-settle sequences, event-driven (``[sequence]``, ``docs/scenario-format.md``): each step's carriages
start together (plus any per-step delay) with seven-segment S-curves to their targets, the step stops when
the last one arrives, and the next step starts once every window has held for ``measure`` seconds.

Each step is simulated from the previous step's end state as its own short run (local time from 0, the
step's moves as inputs), DOP853 steps between the profiles' breakpoints (and the leveling valves' switches,
:mod:`isolator.simulation.valve_events`), extended in chunks until the
window rule (:mod:`isolator.simulation.sequence_rule`) is decided on a 1 kHz grid read from the dense output;
the part after the step's end is dropped and the runs are stitched with their time offsets.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from isolator.errors import ScenarioError, SimulationError, UnstableTableError
from isolator.model.cache import get_model
from isolator.model.equilibrium import Equilibrium, air_in_groups, static_equilibria
from isolator.model.parameters import ParameterLayout
from isolator.model.tipping import rocking_over, tipping_verdict, travel_configurations
from isolator.numerics.dop853 import DenseStepper, StepPlan, step_plan
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.profiles import Profile
from isolator.scenario.sequence import held
from isolator.simulation.points import point_positions
from isolator.simulation.resources import check_run_memory
from isolator.simulation.sequence_moves import MoveDesign, step_profiles
from isolator.simulation.sequence_result import SequenceResult, StepResult
from isolator.simulation.sequence_rule import held_from, normalised
from isolator.simulation.stepping import (
    DENSE_STEP_ANGLE,
    MAX_DENSE_STEP,
    check_step_count,
    dense_stepper,
    staged_map,
)
from isolator.simulation.valve_events import ValveSwitches, step_on_switches, with_switches
from isolator.simulation.window_random import with_random_margins

__all__ = ["MoveDesign", "SequenceResult", "StepResult", "run_sequence"]

#: the grid the window rule is read on [Hz] (global time k / RULE_RATE)
RULE_RATE = 1000.0
#: the shortest extension of a step's run while its rule is undecided [s]
MIN_CHUNK = 0.25


@dataclass
class _Chunk:
    """One DOP853 run: global times ``t0 .. t1`` (the valid part), its plan in chunk time from 0."""

    t0: float
    t1: float
    step: int
    plan: StepPlan
    polynomials: np.ndarray

    def states(self, t: np.ndarray) -> np.ndarray:
        return DenseStepper.states_at(self.plan, self.polynomials, np.asarray(t, dtype=float) - self.t0)


class _Runner:
    """A sequence scenario's model, parameters, equilibria (cached by configuration) and chunk runs."""

    def __init__(self, scenario: Scenario, model: str, p: np.ndarray | None = None) -> None:
        check_run_memory(scenario)  # the output grid the result is read on
        self.scenario = scenario
        self.layout = ParameterLayout.of(scenario)
        self.model = get_model(self.layout, model)
        self.p = self.layout.pack(scenario) if p is None else self.layout.checked(p, "parameters")
        self.names = tuple(c.name for c in scenario.carriages)
        assert scenario.sequence is not None
        initial = scenario.sequence.initial_positions(self.names)  # the sequence's, whatever the carriages hold
        first = static_equilibria(self.model, self.p[None, :], initial,
                                  "with the carriages at the sequence's initial positions")[0]
        self.start = first
        self.air = None if self.layout.pneumatic is None else air_in_groups(self.model, first.state[None, :],
                                                                                self.p[None, :])
        self._equilibria: dict[bytes, Equilibrium] = {initial.tobytes(): first}
        self.switches = ValveSwitches.of(scenario, self.layout, self.p)
        self._still: dict[int, np.ndarray] = {}  # the staged rest inputs of each step's profiles
        self.arms = np.array([pt.position for pt in scenario.points], dtype=float).reshape(-1, 3)
        self.origin = point_positions(first.state, self.arms, self.model.kind)[:, :, 0]

    def prepare(self, configurations: np.ndarray) -> None:
        """Solve the equilibria of the steps' configurations side by side (one Newton run); a configuration
        without one is left to :meth:`equilibrium`, whose error names it."""
        todo = [q for q in np.unique(configurations, axis=0) if q.tobytes() not in self._equilibria]
        if not todo:
            return
        try:
            solved = static_equilibria(self.model, self.p[None, :], np.array(todo), "at a step's targets",
                                       air=self.air)
        except UnstableTableError:
            return
        self._equilibria.update((q.tobytes(), e) for q, e in zip(todo, solved, strict=True))

    def equilibrium(self, q: np.ndarray) -> Equilibrium:
        key = np.asarray(q, dtype=float).tobytes()
        if key not in self._equilibria:
            where = "with the carriages parked at " + ", ".join(f"{n} = {v:.6g} m" for n, v in zip(self.names, q,
                                                                                               strict=True))
            self._equilibria[key] = static_equilibria(self.model, self.p[None, :], np.asarray(q, dtype=float), where,
                                                      air=self.air)[0]
        return self._equilibria[key]

    def check_tipping(self) -> None:
        """Refuse a sequence that would tip the table, in ``isolator stability``'s words (its configurations:
        every combination of each carriage's least, middle and greatest coordinate over the steps)."""
        configs = travel_configurations(self.scenario)
        stable, _, line = tipping_verdict(configs, rocking_over(get_model(self.layout, "exact"), self.p, configs))
        if not stable:
            raise UnstableTableError(line)

    def settled_points(self, q: np.ndarray) -> np.ndarray:
        """Every point's displacement [m] (points, 3) at the static equilibrium with the carriages at ``q``."""
        return point_positions(self.equilibrium(q).state, self.arms, self.model.kind)[:, :, 0] - self.origin

    def max_step(self, omega: float) -> float:
        key = max(0, math.ceil(8 * math.log2(MAX_DENSE_STEP * max(omega, 1e-12) / DENSE_STEP_ANGLE)))
        return MAX_DENSE_STEP * 2.0 ** (-key / 8)

    def run_chunk(self, x0: np.ndarray, profiles: tuple[Profile, ...], step_start: float, a: float, b: float,
                  max_step: float, step: int) -> _Chunk:
        """Integrate from ``x0`` over the step's local times ``a .. b`` [s] (global ``step_start + a ..``)."""
        length = b - a
        ground = self.scenario.ground
        knots = {float(k) - a for prof in profiles for k in prof.breakpoints}
        if ground is not None:
            knots |= {float(k) - a - step_start for k in ground.breakpoints}
        inside = np.array(sorted(k for k in knots if 0.0 < k < length), dtype=float)
        # after the last carriage stops (and with a still floor) every stage has the same inputs: those rows
        # are the rest inputs, staged once
        rest = max((float(prof.stop_time) for prof in profiles), default=0.0)
        if id(profiles) not in self._still:  # once per step (the profiles stay alive in the run's timeline)
            at = np.full((1, 1), rest + 1.0)
            self._still[id(profiles)] = self._inputs(profiles, at, at, step_start)
        still = self._still[id(profiles)]

        def steps(plan: StepPlan) -> np.ndarray | None:
            times, mid = plan.stage_times()
            moving = np.ones(times.shape[0], bool) if self.scenario.has_ground_motion else \
                plan.start + a < rest - 1e-12
            staged = np.empty((times.shape[0], times.shape[1], still.shape[2]))
            if moving.any():
                staged[moving] = self._inputs(profiles, times[moving] + a, mid[moving] + a, step_start)
            staged[~moving] = still[0, 0]
            return dense_stepper(self.model).run_slots(x0, plan, np.ascontiguousarray(staged), self.p,
                                                       self.start.state, with_states=True)[3]

        plan = step_plan(np.array([0.0, length]), inside, max_step, end=length)
        if self.switches is None:
            poly = steps(plan)
        else:  # the steps end on the valves' switches, as a fixed-time run's do
            plan, poly = step_on_switches([self.switches], plan, steps, lambda out: [
                np.zeros((0, 1, 1)) if out is None else out], lambda times: step_plan(
                np.array([0.0, length]), with_switches(inside, times, length), max_step, end=length))
        if poly is None or not np.all(np.isfinite(poly)):
            raise SimulationError(f"the run diverged: non-finite state in step {step} after t = "
                                  f"{step_start + a:.4g} s")
        return _Chunk(step_start + a, step_start + b, step, plan, poly[: plan.steps])

    def _inputs(
        self, profiles: tuple[Profile, ...], times: np.ndarray, mid: np.ndarray, step_start: float
    ) -> np.ndarray:
        """The model's inputs (staged when the model has a staged form) at the step's local ``times`` [s]."""
        layout, ground, n = self.layout, self.scenario.ground, len(profiles)
        u = np.zeros((*times.shape, layout.input_size))
        for i, prof in enumerate(profiles):
            q, v, acc = prof.evaluate(times, mid)
            u[..., i], u[..., n + i], u[..., 2 * n + i] = q, v, acc
        if layout.ground and ground is not None:
            u[..., layout.ground_slice] = ground.displacement(times + step_start, mid + step_start)
        if self.model.staged_inputs is not None and times.size:
            flat = u.reshape(u.shape[0] * u.shape[1], u.shape[2])
            u = staged_map(self.model)(flat, self.p)[0].reshape(*u.shape[:2], -1)
        return u

    def pose_at(self, chunk: _Chunk, t: np.ndarray) -> np.ndarray:
        """The states' position and rotation part (N, 7) at global times ``t`` [s] (what the points need): the
        dense output as :meth:`DenseStepper.states_at` reads it, on those states only."""
        width = 7 if self.model.kind == "exact" else 6
        plan, poly = chunk.plan, chunk.polynomials
        local = np.asarray(t, dtype=float) - chunk.t0
        starts = plan.start[: poly.shape[0]]
        step = np.clip(np.searchsorted(starts, local, side="right") - 1, 0, poly.shape[0] - 1)
        s = ((local - starts[step]) / plan.length[step])[:, None]
        coefficients = poly[step, :, :width]  # (N, degree + 1, width), one gather
        out = coefficients[:, -1]
        for j in range(poly.shape[1] - 2, -1, -1):
            out = coefficients[:, j] + s * out
        return np.asarray(out)

    def point_rows(self, states: np.ndarray, settled: np.ndarray) -> np.ndarray:
        """The windows' deviations from the settled positions divided by their half-widths (rows, N)."""
        names = [pt.name for pt in self.scenario.points]
        moved: dict[int, np.ndarray] = {}
        deviations, widths = [], []
        for w in self.scenario.windows:
            i, axes = names.index(w.point), list(w.axis_indices)
            if i not in moved:
                moved[i] = self._moved(states, i)
            deviations.append(moved[i][axes] - settled[i, axes, None])
            widths.append(w.half_widths[:, None])
        return normalised(deviations, widths)

    def _moved(self, states: np.ndarray, i: int) -> np.ndarray:
        """Point ``i``'s displacement (3, N) [m] at states (N, >= 7): :func:`point_positions` for one point,
        the exact model's quaternion turning the lever arm without building the matrices."""
        if self.model.kind != "exact":
            return point_positions(states, self.arms[i : i + 1], self.model.kind)[0] - self.origin[i, :, None]
        w, x, y, z = states[:, 3], states[:, 4], states[:, 5], states[:, 6]
        s = 2.0 / (w * w + x * x + y * y + z * z)
        a0, a1, a2 = self.arms[i]
        xx, yy, zz, xy, xz, yz, wx, wy, wz = x * x, y * y, z * z, x * y, x * z, y * z, w * x, w * y, w * z
        out = np.empty((3, states.shape[0]))
        out[0] = states[:, 0] + a0 + s * (-(yy + zz) * a0 + (xy - wz) * a1 + (xz + wy) * a2)
        out[1] = states[:, 1] + a1 + s * ((xy + wz) * a0 - (xx + zz) * a1 + (yz - wx) * a2)
        out[2] = states[:, 2] + a2 + s * ((xz - wy) * a0 + (yz + wx) * a1 - (xx + yy) * a2)
        return out - self.origin[i, :, None]


def _rule_times(step_start: float, a: float, b: float, stop: float) -> np.ndarray:
    """The rule's grid in the step's local time within (a, b]: global multiples of 1 / RULE_RATE after the stop,
    and the stop itself when it falls in this chunk."""
    lo = max(a, stop)
    k0 = math.floor((step_start + lo) * RULE_RATE) + 1
    k1 = math.floor((step_start + b) * RULE_RATE * (1 + 1e-15))
    grid = np.arange(k0, k1 + 1) / RULE_RATE - step_start
    grid = grid[(grid > lo + 1e-12) & (grid <= b + 1e-12)]
    return np.concatenate([[stop], grid]) if a <= stop <= b else grid


def run_sequence(
    scenario: Scenario, model: str = "exact", move: MoveDesign | None = None, parameters: np.ndarray | None = None
) -> SequenceResult:
    """Simulate a scenario's ``[sequence]``: step, settle, measure, next step.

    Parameters
    ----------
    scenario : Scenario
        With a ``[sequence]`` and at least one ``[[windows]]``.
    model : {"exact", "paper"}
    move : callable, optional
        ``move(step_index, carriage_name, q_from, q_to, limits) -> Profile``: each named carriage's move in
        the step's local time (the step starts at 0; its ``delay`` is not added), at rest at ``q_from``
        [m] before and at ``q_to`` [m] after its last breakpoint, which is the move's stop; ``limits`` are the
        step's S-curve limits (:class:`~isolator.scenario.definitions.MotionLimits`). Default: the
        seven-segment S-curve at those limits, started after the step's ``delay``.
    parameters : ndarray, optional
        A whole parameter vector (``Simulator(scenario).layout`` order; a design of a sweep or study),
        checked by the rules the file reader checks by; default the scenario's.

    Returns
    -------
    SequenceResult
        Each step's start, stop, settled and end times [s], the total time [s] and the throughput [steps per
        hour].

    Raises
    ------
    ScenarioError
        No ``[sequence]`` or no ``[[windows]]``.
    ParameterError
        A ``move`` that does not return a stopping profile from ``q_from`` to ``q_to``.
    UnstableTableError, SimulationError
        A configuration that tips the table; a run that diverges.

    Examples
    --------
    >>> from isolator import load_scenario, run_sequence
    >>> result = run_sequence(load_scenario("paper-table-3-2-sequence"))  # doctest: +SKIP
    >>> result.total_time, result.throughput  # doctest: +SKIP
    """
    sequence = scenario.sequence
    if sequence is None:
        raise ScenarioError("sequence: the scenario has no [sequence] (steps to run); see docs/scenario-format.md")
    if not scenario.windows:
        raise ScenarioError("windows: a [sequence] needs at least one [[windows]] to tell when a step has settled")
    runner = _Runner(scenario, model, parameters)
    runner.scenario = with_random_margins(scenario, runner.p)  # the windows less the random motion's room
    names = runner.names
    runner.check_tipping()
    runner.prepare(sequence.configurations(names))
    duration = scenario.simulation.duration
    q = sequence.initial_positions(names)
    x = runner.start.state
    chunks: list[_Chunk] = []
    timeline: list[tuple[float, tuple[Profile, ...]]] = [(0.0, tuple(held(v) for v in q))]
    omega = runner.start.max_frequency
    if sequence.start > 0:  # at rest (or on the moving floor) until the first step
        b = min(sequence.start, duration)
        chunks.append(runner.run_chunk(x, timeline[0][1], 0.0, 0.0, b, runner.max_step(omega), -1))
        x = chunks[-1].states(np.array([b]))[0]
    now = min(sequence.start, duration)
    results: list[StepResult] = []
    settled_points: list[np.ndarray] = []
    unsettled: int | None = None
    guess = 1.0 + sequence.measure
    for k in range(len(sequence.steps)):
        profiles, target, stop = step_profiles(runner.scenario, k, q, move)
        settled = runner.settled_points(target)
        omega = max(omega, runner.equilibrium(target).max_frequency)
        h = runner.max_step(omega)
        available = duration - now
        check_step_count(omega, max(available, 0.0), DENSE_STEP_ANGLE, runner.scenario)
        timeline.append((now, profiles))
        settled_points.append(settled)
        found: float | None = None
        t_rule: list[np.ndarray] = []
        rows: list[np.ndarray] = []
        a, b, x_chunk = 0.0, min(stop + guess, available), x
        while available > 1e-12:
            chunk = runner.run_chunk(x_chunk, profiles, now, a, b, h, k)
            chunks.append(chunk)
            if b >= stop:
                times = _rule_times(now, a, b, stop)
                t_rule.append(times)
                rows.append(runner.point_rows(runner.pose_at(chunk, times + now), settled))
                found = held_from(np.concatenate(t_rule), np.hstack(rows), sequence.measure)
                if found is not None:
                    break
            if b >= available - 1e-12:
                break
            x_chunk = chunk.states(np.array([now + b]))[0]
            a, b = b, min(b + max(MIN_CHUNK, 0.5 * (b - stop)), available)  # growing: few chunks, little overrun
        where = tuple((n, float(v)) for n, v in zip(names, target, strict=True))
        if found is None:
            unsettled = k
            results.append(StepResult(k, now, now + stop, None, None, where))
            if chunks:
                chunks[-1].t1 = min(chunks[-1].t1, duration)
            break
        end = found + sequence.measure
        results.append(StepResult(k, now, now + stop, now + found, now + end, where))
        while chunks[-1].t0 > now + end + 1e-12 and chunks[-1].step == k:
            chunks.pop()
        chunks[-1].t1 = now + end
        x = chunks[-1].states(np.array([now + end]))[0]
        guess = max(found - stop, 0.0) * 1.03 + sequence.measure + 0.02
        q = target
        now += end
    return SequenceResult.stitch(runner.scenario, runner.model.kind, runner.model.variant.signals, runner.start.state,
                                 runner.arms, runner.origin, chunks, timeline, tuple(results),
                                 tuple(settled_points), unsettled)


def chain_scenario(scenario: Scenario, result: SequenceResult, after: float = 0.0) -> Scenario:
    """The sequence's moves as an ordinary scenario: each carriage's profile the chain of its steps' moves at
    the steps' start times (:func:`~isolator.simulation.sequence_result.chain_profiles`), no ``[sequence]``,
    running until the last step's end (the run's end when a step did not settle) plus ``after`` [s].
    Simulating it gives the same response as the sequence (a check, and the fixed-time baseline of the
    benchmark)."""
    from isolator.simulation.sequence_result import chain_profiles

    profiles = chain_profiles(result)
    carriages = tuple(replace(c, profile=prof) for c, prof in zip(scenario.carriages, profiles, strict=True))
    last = result.steps[-1].end if result.steps and result.steps[-1].end is not None else None
    end = scenario.simulation.duration if last is None else last
    simulation = replace(scenario.simulation, duration=float(end + after))
    return replace(scenario, carriages=carriages, sequence=None, simulation=simulation)


check_public(globals(), ("run_sequence"))
