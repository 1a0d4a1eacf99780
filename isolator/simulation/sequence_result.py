"""What a step-and-settle sequence gives (:func:`isolator.run_sequence`): per step start, stop, settled and end
times; the total time and throughput; the response at the output samples (the six table signals, the
carriages, the ``[[points]]``); CSV, JSON and a figure."""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import SIGNALS, Scenario
from isolator.scenario.output_files import atomic_output
from isolator.scenario.profiles import PiecewisePolynomialProfile, Profile
from isolator.scenario.readable import length_text
from isolator.simulation.points import point_positions

if TYPE_CHECKING:
    from isolator.scenario.windows import Window

__all__ = ["STEP_COLUMNS", "SequenceResult", "StepResult", "chain_profiles"]

#: the columns of ``steps.csv`` (s)
STEP_COLUMNS = ("step", "start", "stop", "settled", "end", "move", "settle")


@dataclass(frozen=True)
class StepResult:
    """One step's times [s] from the sequence's t = 0 (None where the step did not settle in the run).

    Attributes
    ----------
    index : int
    start : float
        When its carriages start.
    stop : float
        When its last carriage arrives.
    settled : float or None
        The start of the first interval of ``measure`` seconds after the stop over which every window holds.
    end : float or None
        ``settled + measure``: when the next step starts.
    targets : tuple of (str, float)
        Every carriage's coordinate once the step has stopped [m].
    """

    index: int
    start: float
    stop: float
    settled: float | None
    end: float | None
    targets: tuple[tuple[str, float], ...] = ()

    @property
    def move(self) -> float:
        """``stop - start`` [s]."""
        return self.stop - self.start

    @property
    def settle(self) -> float | None:
        """``settled - stop`` [s] (None if not settled)."""
        return None if self.settled is None else self.settled - self.stop

    def to_dict(self) -> dict[str, Any]:
        return {"step": self.index, "start": self.start, "stop": self.stop, "settled": self.settled,
                "end": self.end, "move": self.move, "settle": self.settle, "targets": dict(self.targets)}


@dataclass(frozen=True)
class SequenceResult:
    """A step-and-settle run.

    Attributes
    ----------
    name, model : str
        The scenario's name; "exact" or "paper".
    steps : tuple of StepResult
        The steps that ran, in order (the last one unsettled when :attr:`unsettled` is set).
    step_count : int
        Steps in the sequence (more than ``len(steps)`` when one did not settle).
    measure : float
        [s]
    unsettled : int or None
        The step that did not settle within ``[simulation] duration`` (no later step ran).
    duration : float
        The run's limit [s].
    carriage_names, point_names : tuple of str
    settled_points : ndarray (steps, points, 3)
        Each step's settled point displacements [m] (static equilibrium at its targets).
    windows : tuple of Window
    profiles : tuple of (float, tuple of Profile)
        Each step's start [s] and carriage profiles in its local time (first: the rest before the first step).
    sampled : callable
        Computes the response at the output samples on first use (:attr:`t`, :attr:`signals`, :attr:`q`,
        :attr:`point_signals`, :attr:`step_of_sample`, :attr:`states`): ``t`` from 0 to the last step's end
        (to the duration when a step did not settle), the table signals from the initial equilibrium, each
        point's world displacement from its initial position [m].
    """

    name: str
    model: str
    steps: tuple[StepResult, ...]
    step_count: int
    measure: float
    unsettled: int | None
    duration: float
    carriage_names: tuple[str, ...]
    point_names: tuple[str, ...]
    settled_points: np.ndarray
    windows: tuple[Window, ...]
    profiles: tuple[tuple[float, tuple[Profile, ...]], ...]
    sampled: Callable[[], tuple[np.ndarray, ...]] = field(repr=False, compare=False)

    # -- the response at the output samples, computed on first use ----------------------------------------
    @cached_property
    def _samples(self) -> tuple[np.ndarray, ...]:
        return self.sampled()

    @property
    def t(self) -> np.ndarray:
        """Output sample times [s] (N,)."""
        return self._samples[0]

    @property
    def signals(self) -> np.ndarray:
        """The six table signals (6, N) [m, rad]."""
        return self._samples[1]

    @property
    def q(self) -> np.ndarray:
        """Carriage coordinates (carriages, N) [m]."""
        return self._samples[2]

    @property
    def point_signals(self) -> np.ndarray:
        """Point displacements (points, 3, N) [m]."""
        return self._samples[3]

    @property
    def step_of_sample(self) -> np.ndarray:
        """The step each sample belongs to (N,), -1 before the first."""
        return self._samples[4]

    @property
    def states(self) -> np.ndarray:
        """The model's states at the samples (N, n_states)."""
        return self._samples[5]

    @classmethod
    def stitch(
        cls, scenario: Scenario, kind: str, signals: Callable[[np.ndarray, np.ndarray], np.ndarray],
        start_state: np.ndarray, arms: np.ndarray, origin: np.ndarray, chunks: Sequence[Any],
        timeline: Sequence[tuple[float, tuple[Profile, ...]]], steps: tuple[StepResult, ...],
        settled: tuple[np.ndarray, ...], unsettled: int | None,
    ) -> SequenceResult:
        """The result from the runs (``chunks``: ``t0``, ``t1``, ``states(t)``), read at the output samples
        on first use."""
        rate = scenario.simulation.sample_rate
        end = max((c.t1 for c in chunks), default=0.0)
        n_carriages = len(scenario.carriages)

        def sampled() -> tuple[np.ndarray, ...]:
            t = np.arange(math.floor(end * rate * (1 + 1e-12)) + 1) / rate
            states = np.tile(start_state, (t.size, 1)).reshape(t.size, start_state.size)
            for c in chunks:
                pick = (t > c.t0 - 1e-12) & (t <= c.t1 + 1e-12)
                if pick.any():
                    states[pick] = c.states(t[pick])
            starts = np.array([s for s, _ in timeline])
            owner = np.searchsorted(starts[1:], t + 1e-12, side="right") - 1
            q = np.zeros((n_carriages, t.size))
            for j, (t0, profiles) in enumerate(timeline):
                pick = owner == j - 1
                for i, prof in enumerate(profiles):
                    q[i, pick] = prof.evaluate(t[pick] - t0)[0]
            moved = point_positions(states, arms, kind) - origin[:, :, None] if arms.size else np.zeros((0, 3, t.size))
            table = np.ascontiguousarray(np.asarray(signals(states, start_state)).reshape(6, t.size))
            return t, table, q, moved, owner, states

        return cls(
            name=scenario.name, model=kind, steps=steps,
            step_count=len(scenario.sequence.steps) if scenario.sequence is not None else len(steps),
            measure=scenario.sequence.measure if scenario.sequence is not None else 0.0,
            unsettled=unsettled, duration=scenario.simulation.duration,
            carriage_names=tuple(c.name for c in scenario.carriages),
            point_names=tuple(pt.name for pt in scenario.points),
            settled_points=np.array(settled).reshape(len(settled), len(scenario.points), 3),
            windows=scenario.windows, profiles=tuple(timeline), sampled=sampled,
        )

    # -- figures of merit --------------------------------------------------------------------------------
    @property
    def total_time(self) -> float | None:
        """First step's start to last step's end [s]; None when a step did not settle."""
        if self.unsettled is not None or not self.steps or self.steps[-1].end is None:
            return None
        return self.steps[-1].end - self.steps[0].start

    @property
    def throughput(self) -> float | None:
        """Steps per hour over :attr:`total_time` (None when a step did not settle or it is 0)."""
        total = self.total_time
        return None if total is None or total <= 0 else 3600.0 * len(self.steps) / total

    def point(self, name: str) -> np.ndarray:
        """The point ``name``'s displacement (3, N) [m]; a KeyError naming the known points."""
        if name not in self.point_names:
            raise KeyError(f"point: unknown '{name}' (points: {', '.join(self.point_names) or 'none'})")
        return self.point_signals[self.point_names.index(name)]

    def deviation(self, name: str) -> np.ndarray:
        """The point ``name``'s deviation (3, N) [m] from the settled position of the step each sample
        belongs to (from its initial position before the first step)."""
        moved = self.point(name)
        i = self.point_names.index(name)
        ref = np.zeros((3, self.t.size))
        has = self.step_of_sample >= 0
        ref[:, has] = self.settled_points[self.step_of_sample[has], i].T
        return moved - ref

    # -- output ------------------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """JSON: ``steps`` (each ``start, stop, settled, end, move, settle`` [s] and ``targets``, every carriage's
        coordinate after the step [m]), ``total_time`` [s],
        ``throughput_per_hour``, ``unsettled`` (step index or null), ``measure``, ``steps_in_sequence``,
        ``move_time``/``settle_time`` (sums over the settled steps [s]), ``settle_time_max``."""
        settles = [s.settle for s in self.steps if s.settle is not None]
        return {
            "name": self.name, "model": self.model,
            "steps": [s.to_dict() for s in self.steps],
            "total_time": self.total_time, "throughput_per_hour": self.throughput,
            "unsettled": self.unsettled, "measure": self.measure, "steps_in_sequence": self.step_count,
            "duration": self.duration,
            "move_time": sum(s.move for s in self.steps if s.settled is not None),
            "settle_time": sum(settles), "settle_time_max": max(settles, default=None),
            "windows": [{"point": w.point, "translation": w.translation, "axes": list(w.axes)} for w in self.windows],
        } | ({"window_random": [w.random_margins for w in self.windows]}
             if any(w.random is not None for w in self.windows) else {})

    def write_steps(self, path: str | Path) -> Path:
        """Write ``step,start,stop,settled,end,move,settle`` [s] per step (empty where not settled)."""
        path = Path(path)
        with atomic_output(path, newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(STEP_COLUMNS)
            for s in self.steps:
                row = s.to_dict()
                writer.writerow([s.index, *("" if row[k] is None else f"{row[k]:.10g}" for k in STEP_COLUMNS[1:])])
        return path

    def write_response(self, path: str | Path) -> Path:
        """Write ``t,x,y,z,rx,ry,rz,q:<carriage>...`` [s, m, rad], ``<point>:x,<point>:y,<point>:z`` [m] per
        point (as ``isolator simulate --out``), then ``step`` (the step each sample belongs to, -1 before)."""
        path = Path(path)
        header = ["t", *SIGNALS, *[f"q:{n}" for n in self.carriage_names],
                  *[f"{n}:{a}" for n in self.point_names for a in "xyz"], "step"]
        data = np.column_stack([self.t, self.signals.T, self.q.T, self.point_signals.reshape(-1, self.t.size).T])
        with atomic_output(path, newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(header)
            for row, step in zip(data, self.step_of_sample, strict=True):
                writer.writerow([*(f"{v:.10g}" for v in row), int(step)])
        return path

    def summary(self) -> str:
        """The per-step table, the total time and the throughput."""
        def f(v: float | None) -> str:
            return f"{v:10.4f}" if v is not None else f"{'-':>10}"

        lines = [f"{self.name} ({self.model} model): {self.step_count} steps, measure {self.measure:g} s, windows "
                 + "; ".join(f"{w.point} ±{length_text(w.translation)} on {','.join(w.axes)}" for w in self.windows),
                 f"{'step':>4} " + " ".join(f"{k + ' [s]':>10}" for k in STEP_COLUMNS[1:])]
        for s in self.steps:
            lines.append(f"{s.index:>4} " + " ".join(f(v) for v in (s.start, s.stop, s.settled, s.end, s.move,
                                                                      s.settle)))
        if self.unsettled is not None:
            lines.append(f"step {self.unsettled} did not settle within the run's {self.duration:g} s "
                         "([simulation] duration); later steps did not run")
        else:
            total = self.total_time or 0.0
            lines.append(f"total time: {total:.4f} s for {len(self.steps)} steps; throughput: "
                         f"{self.throughput or 0.0:.1f} steps per hour")
        return "\n".join(lines)

    def plot(self, point: str | None = None, title: str | None = None) -> Any:
        """A figure: the point's deviation from each step's settled position [nm] against time, the window
        shaded, each step's move, settle and measure as coloured spans (``point``: default the first
        window's)."""
        from isolator.simulation.sequence_figure import plot_sequence

        return plot_sequence(self, point, title)


def chain_profiles(result: SequenceResult) -> tuple[PiecewisePolynomialProfile, ...]:
    """Each carriage's steps' moves as one profile in the sequence's time: every step's piecewise
    polynomial shifted to the step's start, held between moves (a fixed-time run of the same moves)."""
    out = []
    for i, name in enumerate(result.carriage_names):
        knots: list[float] = [0.0]
        coefficients: list[tuple[float, ...]] = []
        q = float(result.profiles[0][1][i].position(0.0))
        for start, profiles in result.profiles[1:]:
            prof = profiles[i]
            if not isinstance(prof, PiecewisePolynomialProfile):
                raise ParameterError(f"move: carriage '{name}': a '{type(prof).__name__}' cannot be chained "
                                     "(piecewise polynomials only)")
            if prof.kind == "hold" or prof.knots[-1] <= prof.knots[0]:
                continue
            first = start + float(prof.knots[0])
            if first > knots[-1]:
                coefficients.append((q, 0.0, 0.0, 0.0))
                knots.append(first)
            width = max(len(c) for c in prof.coefficients)
            coefficients += [tuple(c) + (0.0,) * (width - len(c)) for c in prof.coefficients]
            knots += [start + float(k) for k in prof.knots[1:]]
            q = float(prof.position(float(prof.knots[-1]) + 1.0))
        if not coefficients:
            coefficients.append((q, 0.0, 0.0, 0.0))
            knots.append(0.0)
        width = max(len(c) for c in coefficients)
        padded = tuple(tuple(c) + (0.0,) * (width - len(c)) for c in coefficients)
        out.append(PiecewisePolynomialProfile(tuple(knots), padded, kind="chain"))
    return tuple(out)


check_public(globals(), ("SequenceResult", "StepResult"))
