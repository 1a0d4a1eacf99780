"""Many runs of one scenario with the isolators' stiffness and damping scaled per run.

The runs' static equilibria are solved side by side; each run gets its own
DOP853 step plan (from its fastest mode, on a ladder of step lengths shared
with single runs). Runs that share a plan are stepped ``LANES`` at a time, one
per SIMD lane of the compiled loop (:mod:`isolator.numerics.dop853_driver`), in worker
threads; each pack's metrics come from its dense output as a single run's do
(:mod:`isolator.simulation.dense_metrics`), four runs at once.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Literal, Protocol

import numpy as np

from isolator.errors import ParameterError, SimulationError
from isolator.model.equilibrium import Equilibrium
from isolator.model.variants import Model
from isolator.scenario.definitions import Scenario
from isolator.simulation.dense_metrics import DenseRuns, dense_metrics
from isolator.simulation.response import Response
from isolator.simulation.settling import Band, signal_bands, still_signals
from isolator.simulation.stepping import Method, check_turn, dense_stepper, hold_time, rk4_stepper
from isolator.simulation.time_grid import TimeGrid

__all__ = ["BLOCK", "LANES", "BatchResult", "BatchSimulator", "run_batch"]

#: runs per task of a worker thread (their metrics are computed together)
BLOCK = 16
#: runs stepped side by side in one compiled call (AVX holds four doubles)
LANES = 4


@dataclass(frozen=True)
class BatchResult:
    """Metrics of many runs of one scenario with varied parameters.

    Attributes
    ----------
    settling_time : ndarray (runs, 6)
        Per signal [s]; NaN where a run cannot show it.
    settling_time_max : ndarray (runs,)
        [s]; NaN where unavailable.
    peak : ndarray (runs, 6)
        [m or rad]; NaN for a run that diverged.
    failures : mapping of int to str
        Why each diverged run failed, by run index (with ``diverged="record"``).
    band : Band
        How the band was chosen (the scenario's ``[settling]`` rule unless given).
    half_widths : ndarray (runs, 6)
        The band each run's settling time is measured in [m or rad] (own bands: per run; NaN for a run
        that diverged).
    """

    settling_time: np.ndarray
    settling_time_max: np.ndarray
    peak: np.ndarray
    failures: Mapping[int, str] = field(default_factory=dict)
    band: Band = field(default_factory=Band)
    half_widths: np.ndarray = field(default_factory=lambda: np.zeros((0, 6)))

    def run_band(self, i: int) -> Band:
        """The band of run ``i``, resolved (its six half-widths)."""
        return Band(self.band.kind, self.band.fraction, self.band.baseline,
                    tuple(float(v) for v in self.half_widths[i]))


class BatchSimulator(Protocol):
    """What a batch needs of its simulator (:class:`isolator.simulation.simulator.Simulator`)."""

    scenario: Scenario
    model: Model
    grid: TimeGrid
    stop_time: float

    def scaled_parameter_sets(
        self, stiffness: float | Sequence[float], damping: float | Sequence[float]
    ) -> np.ndarray: ...

    def equilibria_of(self, params: np.ndarray) -> tuple[list[Equilibrium], list[Equilibrium | None]]: ...

    def method_for(self, omega_max: float) -> Method: ...

    def plan_inputs(self, method: Method, p: np.ndarray) -> np.ndarray: ...

    def grid_inputs(self, substeps: int) -> np.ndarray: ...

    def signals(self, states: np.ndarray, start: Equilibrium | np.ndarray) -> np.ndarray: ...

    def run_method(self, p: np.ndarray, start: Equilibrium, end: Equilibrium | None, method: Method, *,
                   band: Band | None = None) -> Response: ...


def run_batch(
    sim: BatchSimulator,
    stiffness: Sequence[float],
    damping: Sequence[float],
    workers: int = 2,
    progress: bool = False,
    diverged: Literal["raise", "record"] = "raise",
    band: Band | None = None,
) -> BatchResult:
    """Runs of ``sim``'s scenario with every isolator's stiffness and damping scaled per run.

    Parameters
    ----------
    sim : Simulator
        (or anything with what :class:`BatchSimulator` lists)
    stiffness, damping : sequence of float
        Scale factors, one per run (stiffness > 0, damping >= 0).
    workers : int
        Threads (the compiled stepping releases the GIL).
    progress : bool
        Print a progress line every 10 %.
    diverged : {"raise", "record"}
        A run that diverges (or turns the table past 0.2 rad) stops the batch with
        :class:`SimulationError` ("raise"), or gets NaN metrics and its reason in
        ``BatchResult.failures`` ("record", for sweeps into soft designs).
    band : Band, optional
        The settling band (default: the scenario's ``[settling]`` rule).

    Returns
    -------
    BatchResult
        The same metrics as :meth:`Simulator.run` gives for each run.

    Raises
    ------
    ParameterError
        A scale is not a finite positive number (named by index), or ``diverged`` is unknown.
    UnstableTableError
        A run's table has no stable equilibrium (the message names the run).
    SimulationError
        A run diverged (the message names the run), with ``diverged="raise"``.
    """
    if diverged not in ("raise", "record"):
        raise ParameterError(f"diverged: must be 'raise' or 'record', got {diverged!r}")
    params = sim.scaled_parameter_sets(stiffness, damping)
    n = params.shape[0]
    rule = Band.from_settling(sim.scenario.settling) if band is None else band
    if n == 0:
        return BatchResult(np.zeros((0, 6)), np.zeros(0), np.zeros((0, 6)), {}, rule)
    starts, ends = sim.equilibria_of(params)
    methods: list[Method] = [
        sim.method_for(max(s.max_frequency, e.max_frequency if e else 0.0)) for s, e in zip(starts, ends, strict=True)
    ]
    # built before the threads start; scaling stiffness and damping leaves the staged inputs alone
    plan_inputs = {}
    for method in {m.plan_key: m for m in methods}.values():
        if method.plan is not None:
            plan_inputs[method.plan_key] = sim.plan_inputs(method, params[0])
        else:
            sim.grid_inputs(method.substeps)
            rk4_stepper(sim.model, method.substeps)
    stepper = dense_stepper(sim.model, LANES)
    t = sim.grid.samples
    finals = np.zeros((n, 6))
    stops = ends[0] is not None
    if stops:
        finals = sim.signals(np.array([e.state for e in ends if e is not None]), np.array([s.state for s in starts])).T
    holds = np.array([hold_time(e) for e in ends])
    settling = np.full((n, 6), np.nan)
    peak = np.zeros((n, 6))
    failures: dict[int, str] = {}
    done = [0]

    def failed(i: int, exc: SimulationError) -> None:
        message = f"run {i} (stiffness x{_scale(stiffness, i):g}, damping x{_scale(damping, i):g}): {exc}"
        if diverged == "raise":
            raise SimulationError(message) from None
        failures[i] = message
        peak[i] = np.nan

    def pack(runs: list[int]) -> None:
        """Step ``runs`` (one plan, at most LANES) side by side; their peaks and settling times."""
        method = methods[runs[0]]
        plan = method.plan
        assert plan is not None
        lanes = runs + runs[-1:] * (LANES - len(runs))  # a short pack repeats its last run
        x0 = np.array([starts[i].state for i in lanes])
        raw, step_peaks, deviations, polys = stepper.run_slots(
            x0, plan, plan_inputs[method.plan_key], params[lanes], x0, with_states=True, final=finals[lanes]
        )
        assert polys is not None
        dense = DenseRuns(plan, raw, step_peaks, deviations, polys, x0, sim.model.variant.signals)
        tops, times, _ = dense_metrics(dense, finals[lanes] if stops else None, sim.stop_time,
                                       lambda top: signal_bands(rule, top), holds[lanes])
        for lane, i in enumerate(runs):
            peak[i] = tops[lane]
            try:
                if not np.all(np.isfinite(peak[i])):
                    sig = raw[plan.sample_slots, :, lane]
                    bad = np.argmax(~np.all(np.isfinite(sig), axis=1)) + 1
                    raise SimulationError(f"the run diverged: non-finite state at t = {t[bad]:.4g} s")
                check_turn(peak[i])
            except SimulationError as exc:
                failed(i, exc)
                continue
            settling[i] = np.where(still_signals(rule, peak[i]), 0.0, times[lane]) if stops else times[lane]

    def task(runs: list[int]) -> None:
        """A thread's share: RK4 runs one by one, DOP853 runs in packs of one plan."""
        for i in runs:
            if methods[i].plan is None:
                try:
                    metrics = sim.run_method(params[i], starts[i], ends[i], methods[i], band=rule).settling
                except SimulationError as exc:
                    failed(i, exc)
                    continue
                settling[i] = [np.nan if r.time is None else r.time for r in metrics.values()]
                peak[i] = [r.peak for r in metrics.values()]
        stepped = [i for i in runs if methods[i].plan is not None]
        for lo in range(0, len(stepped), LANES):
            pack(stepped[lo : lo + LANES])
        done[0] += len(runs)
        if progress and n >= 10 and (done[0] * 10) // n != ((done[0] - len(runs)) * 10) // n:
            print(f"  batch: {done[0]}/{n} runs", flush=True)

    # runs of one plan next to each other, so that packs share their plan; tasks of BLOCK runs
    # (a whole number of packs per plan)
    tasks: list[list[int]] = []
    for key in sorted({m.plan_key for m in methods}):
        same = [i for i in range(n) if methods[i].plan_key == key]
        tasks += [same[lo : lo + BLOCK] for lo in range(0, len(same), BLOCK)]
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        list(pool.map(task, tasks))
    with np.errstate(all="ignore"):
        worst = np.where(np.all(np.isfinite(settling), axis=1), np.max(settling, axis=1), np.nan)
    return BatchResult(settling, worst, peak, dict(sorted(failures.items())), rule, rule.resolve(peak))


def _scale(values: Sequence[float], i: int) -> float:
    return float(np.asarray(values, dtype=float).reshape(-1)[i])
