"""Step-and-settle sequences designed for throughput: each step's moves chosen to cut move + settle.

A sequence's total time is the sum over its steps of move, settle (until every window holds) and measure.
The measure is fixed; the rest of a step depends on how its carriages move. This module designs, for
every distinct move, one of several profile families (:data:`FAMILIES`): the seven-segment S-curve alone,
or convolved with input shapers, one per mode the move excites most (ZV or ZVD on the first, ZVD + ZV,
ZV on two or three modes). Within a family it chooses each carriage's S-curve limits (speed,
acceleration, jerk, each at most the carriage's ``limits``), a start delay for each carriage but the
first, and each shaper's frequency and damping about its mode's, judged by the window rule on the exact
time-varying model (:func:`isolator.simulation.sequence.run_sequence`).

The window rule makes the step time a step function of the design (an oscillation peak crossing a
window edge moves the settled time by half a period), so gradients say nothing; the search is a
derivative-free one: a scrambled Sobol set over each family's box (limits as log fractions of the
carriage's, down to :data:`LOWEST_FRACTION`), then Sobol sets in shrinking boxes around the best design.
Steps that make the same move (the same stroke for each carriage) share one design, tuned on the first of
them from rest at its start; the whole optimised sequence is then simulated, and any step that came out
slower than in the starting sequence gets its starting move back, so the result is never slower step by
step (up to the small state a step inherits from the previous one). Each family's start (the carriages'
limits; every shaper at its own mode's frequency and damping) is tried first, so the result is never
worse than those shaped baselines; on the bundled grid those starts win, and the search's part is
choosing the family per move.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import qmc

from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.sequence import Move, Step, sequence_table
from isolator.scenario.shapers import shaper
from isolator.scenario.writing import scenario_data, write_toml
from isolator.simulation.sequence import SequenceResult, run_sequence

from .input_shaping import ExcitedMode
from .sequence_baselines import dominant_modes_at

__all__ = ["LOWEST_FRACTION", "SequenceOptimisation", "optimise_sequence", "write_sequence_scenario"]

#: the smallest fraction of a carriage's limit a designed move may use
LOWEST_FRACTION = 0.05
#: the longest start delay of a step's second and later carriages [s]
MAX_DELAY = 0.5
#: the profile families searched, by name: the S-curve alone, and S-curves convolved with shapers, one per
#: mode the move excites most (the first shaper for the first mode, ...)
FAMILIES: dict[str, tuple[str, ...]] = {
    "scurve": (),
    "zv": ("zv",),
    "zvd": ("zvd",),
    "zv+zv": ("zv", "zv"),
    "zvd+zv": ("zvd", "zv"),
    "zv+zv+zv": ("zv", "zv", "zv"),
}
#: a shaper's frequency is searched within this factor of the dominant mode's
SHAPER_RANGE = 1.4
#: the largest damping ratio a shaper is designed for
MAX_SHAPER_DAMPING = 0.4

MoveKey = tuple[tuple[str, float], ...]


@dataclass(frozen=True)
class SequenceOptimisation:
    """A sequence before and after its steps were designed.

    Attributes
    ----------
    before, after : SequenceResult
        The scenario's sequence and the optimised one, simulated in full.
    scenario : Scenario
        With the optimised ``[sequence]`` (each designed step's limits and delays given explicitly).
    designs : dict
        Per distinct move (carriage name, stroke [m]) the chosen fractions of the carriages' limits
        (velocity, acceleration, jerk) and delays, and its step time (move + settle) from rest [s] before
        and after.
    reverted : tuple of int
        Steps given their starting move back (slower with the shared design).
    evaluations : int
        Single-step simulations run by the search.
    wall_time : float
        [s]
    """

    before: SequenceResult
    after: SequenceResult
    scenario: Scenario
    designs: dict[MoveKey, dict[str, Any]]
    reverted: tuple[int, ...]
    evaluations: int
    wall_time: float
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: total time and throughput before and after, the gain, the designs."""
        b, a = self.before, self.after
        gain = None if not (b.throughput and a.throughput) else a.throughput / b.throughput - 1.0
        return {
            "before": {"total_time": b.total_time, "throughput_per_hour": b.throughput},
            "after": {"total_time": a.total_time, "throughput_per_hour": a.throughput},
            "throughput_gain": gain,
            "moves": [{"move": dict(key), **{k: v for k, v in value.items() if k != "chosen"}}
                      for key, value in self.designs.items()],
            "reverted_steps": list(self.reverted),
            "evaluations": self.evaluations,
            "wall_time": self.wall_time,
            "steps": a.to_dict()["steps"],
        }

    def summary(self) -> str:
        """The totals, the throughput gain and each distinct move's design, a line each."""
        b, a = self.before, self.after
        lines = [f"{'':>10} {'total [s]':>10} {'throughput [steps/h]':>21}"]
        for label, r in (("before", b), ("optimised", a)):
            total = "n/a" if r.total_time is None else f"{r.total_time:.3f}"
            rate = "n/a" if r.throughput is None else f"{r.throughput:.1f}"
            lines.append(f"{label:>10} {total:>10} {rate:>21}")
        data = self.to_dict()
        if data["throughput_gain"] is not None:
            lines.append(f"throughput gain: {data['throughput_gain'] * 100:+.1f} %")
        for key, d in self.designs.items():
            what = ", ".join(f"{n} {s * 1e3:+.4g} mm" for n, s in key)
            limits = "; ".join(f"{n}: v {f[0]:.3g}, a {f[1]:.3g}, j {f[2]:.3g} of its limits"
                               + (f", delay {dl:.3g} s" if dl else "")
                               + "".join(f", {t['kind'].upper()} shaper at {t['frequency']:.4g} Hz, damping "
                                         f"{t['damping']:.3g}" for t in sh)
                               for n, f, dl, sh in zip(d["carriages"], d["fractions"], d["delays"], d["shapers"],
                                                       strict=True))
            lines.append(f"move {what}: {d['before']:.3f} s -> {d['after']:.3f} s from rest ({limits})")
        if self.reverted:
            lines.append(f"steps given their starting move back: {', '.join(map(str, self.reverted))}")
        lines.append(f"{self.evaluations} single-step simulations, {self.wall_time:.1f} s")
        return "\n".join(lines)


def optimise_sequence(
    scenario: Scenario,
    model: str = "exact",
    samples: int = 32,
    rounds: int = 3,
    seed: int = 0,
    progress: bool = False,
) -> SequenceOptimisation:
    """Design every step of a scenario's ``[sequence]`` for the least total time.

    Parameters
    ----------
    scenario : Scenario
        With a ``[sequence]`` (and ``[[windows]]``).
    model : {"exact", "paper"}
    samples : int
        Designs tried per distinct move and family in the first Sobol set (a power of two is best); each
        of the ``rounds`` refinements tries half as many around the best.
    rounds : int
        Refinements (each box half the size of the one before).
    seed : int
        Of the scrambled Sobol sets.
    progress : bool
        A line per distinct move.

    Raises
    ------
    ScenarioError
        No ``[sequence]``, or the starting sequence does not settle within the duration.
    ParameterError
        ``samples`` or ``rounds`` out of range.
    """
    t_start = time.perf_counter()
    sequence = scenario.sequence
    if sequence is None:
        raise ScenarioError("sequence: the scenario has no [sequence] to optimise (isolator optimise-profile "
                            "designs a single move without one)")
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 2:
        raise ParameterError(f"samples: must be a whole number >= 2, got {samples!r}")
    if isinstance(rounds, bool) or not isinstance(rounds, int) or rounds < 0:
        raise ParameterError(f"rounds: must be a whole number >= 0, got {rounds!r}")
    before = run_sequence(scenario, model)
    if before.unsettled is not None:
        raise ScenarioError(f"sequence: step {before.unsettled} of the starting sequence does not settle within "
                            "[simulation] duration; lengthen it before optimising")
    names = tuple(c.name for c in scenario.carriages)
    configs = sequence.configurations(names)
    keys = [_move_key(step, configs[i], names) for i, step in enumerate(sequence.steps)]
    designs: dict[MoveKey, dict[str, Any]] = {}
    counter = [0]
    for i, key in enumerate(keys):
        if not key or key in designs:
            continue
        base_end = before.steps[i].end
        assert base_end is not None  # every step settled (checked above)
        limit = 3.0 * (base_end - before.steps[i].start) + 1.0  # a design three times slower is no candidate
        designs[key] = _design_move(scenario, model, i, configs[i], limit, samples, rounds, seed, counter)
        if progress:
            d = designs[key]
            print(f"  move {', '.join(f'{n} {s * 1e3:+.4g} mm' for n, s in key)}: {d['before']:.3f} s -> "
                  f"{d['after']:.3f} s from rest", flush=True)
    steps = tuple(_designed_step(step, designs.get(keys[i])) for i, step in enumerate(sequence.steps))
    optimised = replace(scenario, sequence=replace(sequence, steps=steps))
    after = run_sequence(optimised, model)
    reverted = _slower_steps(before, after)
    if reverted:
        steps = tuple(sequence.steps[i] if i in reverted else s for i, s in enumerate(steps))
        optimised = replace(scenario, sequence=replace(sequence, steps=steps))
        after = run_sequence(optimised, model)
    return SequenceOptimisation(before, after, optimised, designs, tuple(reverted), counter[0],
                                time.perf_counter() - t_start)


def _move_key(step: Step, q: np.ndarray, names: tuple[str, ...]) -> MoveKey:
    """The step's move: (carriage, stroke [m]) of each carriage that moves, strokes rounded to 1 nm."""
    index = {n: i for i, n in enumerate(names)}
    return tuple((n, round(m.target - float(q[index[n]]), 9)) for n, m in step.moves
                 if round(m.target - float(q[index[n]]), 9) != 0.0)


def _step_time(scenario: Scenario, model: str, step: Step, q: np.ndarray, limit: float) -> float:
    """Move + settle [s] of ``step`` alone, from rest with the carriages at ``q`` (inf: not within
    ``limit`` seconds)."""
    sequence = scenario.sequence
    assert sequence is not None
    names = [c.name for c in scenario.carriages]
    alone = replace(sequence, steps=(step,), start=0.0, initial=tuple(zip(names, map(float, q), strict=True)))
    settings = replace(scenario.simulation, duration=limit)
    result = run_sequence(replace(scenario, sequence=alone, simulation=settings), model)
    first = result.steps[0]
    return math.inf if first.settled is None else first.settled - first.start


def _design_move(
    scenario: Scenario, model: str, index: int, q: np.ndarray, limit: float, samples: int, rounds: int, seed: int,
    counter: list[int],
) -> dict[str, Any]:
    """The best design of step ``index``'s move: per family, Sobol sets in shrinking boxes from its start."""
    sequence = scenario.sequence
    assert sequence is not None
    step = sequence.steps[index]
    names = tuple(c.name for c in scenario.carriages)
    moving = [n for n, _ in _move_key(step, q, names)]
    parked = tuple(map(float, sequence.configurations(names)[index + 1]))
    deepest = max(len(kinds) for kinds in FAMILIES.values())
    modes = [dominant_modes_at(scenario, names.index(n), parked)[:deepest] for n in moving]
    best: tuple[float, str, np.ndarray] | None = None
    first = math.inf
    for family, kinds in FAMILIES.items():
        if any(len(found) < len(kinds) for found in modes):
            continue  # fewer excited modes than the family shapes
        low, high, start = _box(len(kinds), len(moving))

        def cost(x: np.ndarray, kinds: tuple[str, ...] = kinds) -> float:
            counter[0] += 1
            return _step_time(scenario, model, _candidate(scenario, step, moving, x, kinds, modes), q, limit)

        best_x, value = start, cost(start)
        if not kinds:
            first = value  # the step as written: every carriage at its limits
        centre, half, count = (low + high) / 2, (high - low) / 2, samples
        for r in range(rounds + 1):
            unit = qmc.Sobol(d=low.size, scramble=True, seed=seed + r).random(count)
            for x in np.clip(centre + (2 * unit - 1) * half, low, high):
                trial = cost(x)
                if trial < value:
                    best_x, value = x, trial
            centre, half, count = best_x, half / 2, max(4, count // 2)
        if best is None or value < best[0]:
            best = (value, family, best_x)
    assert best is not None
    value, family, x = best
    chosen = dict(_candidate(scenario, step, moving, x, FAMILIES[family], modes).moves)
    return {"step": index, "family": family, "carriages": moving,
            "fractions": np.exp(x[: 3 * len(moving)]).reshape(len(moving), 3).tolist(),
            "delays": [chosen[n].delay for n in moving],
            "limits": [[chosen[n].velocity, chosen[n].acceleration, chosen[n].jerk] for n in moving],
            "shapers": [[{"kind": t.kind, "frequency": t.frequency, "damping": t.damping} for t in chosen[n].shapers]
                        for n in moving],
            "before": first, "after": value, "chosen": chosen}


def _box(shapers: int, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The search box (low, high) of a family's parameters and its start: per moving carriage (``n``) the log
    fractions of its velocity, acceleration and jerk limits, the delays of all but the first, then for each of
    its ``shapers`` the log frequency over its mode's, and the shapers' damping ratios."""
    low = [math.log(LOWEST_FRACTION)] * (3 * n) + [0.0] * (n - 1)
    high = [0.0] * (3 * n) + [MAX_DELAY] * (n - 1)
    start = [0.0] * (3 * n) + [0.0] * (n - 1)
    if shapers:
        low += [math.log(1 / SHAPER_RANGE)] * (n * shapers) + [0.0] * (n * shapers)
        high += [math.log(SHAPER_RANGE)] * (n * shapers) + [MAX_SHAPER_DAMPING] * (n * shapers)
        start += [0.0] * (n * shapers) + [-1.0] * (n * shapers)  # -1: the mode's own damping (see _candidate)
    return np.array(low), np.array(high), np.array(start)


def _candidate(scenario: Scenario, step: Step, moving: list[str], x: np.ndarray, kinds: tuple[str, ...] = (),
               modes: list[list[ExcitedMode]] | None = None) -> Step:
    """``step`` with each moving carriage's limits scaled by ``exp(x)``, its delay from ``x`` and, for each of
    the shaper ``kinds``, a shaper tuned from the carriage's next most excited mode by ``x`` (a damping
    below 0: the mode's own)."""
    limits = {c.name: c.limits for c in scenario.carriages}
    n, m = len(moving), len(kinds)
    moves = []
    for name, move in step.moves:
        if name not in moving:
            moves.append((name, move))
            continue
        k = moving.index(name)
        lim = limits[name]
        f = np.exp(x[3 * k: 3 * k + 3])
        delay = float(x[3 * n + k - 1]) if k > 0 else 0.0
        trains = []
        for j, kind in enumerate(kinds if modes is not None else ()):
            mode = modes[k][j] if modes is not None else None
            assert mode is not None
            frequency = float(mode.frequency) * math.exp(float(x[4 * n - 1 + k * m + j]))
            given = float(x[4 * n - 1 + n * m + k * m + j])
            trains.append(shaper(kind, frequency, float(mode.damping) if given < 0 else given))
        moves.append((name, Move(move.target, _scaled(lim.velocity, f[0]), _scaled(lim.acceleration, f[1]),
                                 _scaled(lim.jerk, f[2]), delay, tuple(trains))))
    return Step(tuple(moves))


def _scaled(limit: float | None, fraction: float) -> float:
    """``fraction`` of ``limit``, never above it (a fraction of 1 gives the limit itself)."""
    if limit is None:  # the reader refuses a sequence's carriage without full limits; a hand-built one may not
        raise ScenarioError("carriages.limits: a carriage a [sequence] moves needs velocity, acceleration and jerk "
                            "limits")
    return float(limit) if fraction >= 1.0 else min(float(limit), float(limit) * float(fraction))


def _designed_step(step: Step, design: dict[str, Any] | None) -> Step:
    """``step`` with a distinct move's designed moves (its own targets kept)."""
    if design is None:
        return step
    chosen = design["chosen"]
    return Step(tuple((name, replace(chosen[name], target=move.target) if name in chosen else move)
                      for name, move in step.moves))


def _slower_steps(before: SequenceResult, after: SequenceResult) -> list[int]:
    """Steps whose move + settle + measure came out longer than in the starting sequence (by > 1 ms)."""
    slower = []
    for i, b in enumerate(before.steps):
        a = after.steps[i] if i < len(after.steps) else None
        if a is None or a.end is None or b.end is None or (a.end - a.start) > (b.end - b.start) + 1e-3:
            slower.append(i)
    return slower


def write_sequence_scenario(source: str | Path | None, scenario: Scenario, path: str | Path,
                            name: str | None = None) -> Path:
    """Write the source scenario file with its ``[sequence]`` replaced by ``scenario``'s (every designed
    step's limits and delays explicit, numbers to 17 digits: reading it back gives the same sequence).

    Raises
    ------
    ScenarioError
        ``scenario`` has no sequence.
    """
    if scenario.sequence is None:
        raise ScenarioError("sequence: nothing to write, the scenario has no [sequence]")
    origin, data = scenario_data(source)
    data["sequence"] = sequence_table(scenario.sequence)
    data["name"] = name or f"{data.get('name', origin.stem)}-optimised"
    return write_toml(data, path)


check_public(globals())
