"""Many runs of one scenario, one parameter vector per run.

The runs' static equilibria are solved side by side; each run gets its own
DOP853 step plan (from its fastest mode, on a ladder of step lengths shared
with single runs). Runs that share a plan are stepped ``LANES`` at a time, one
per SIMD lane of the compiled loop (:mod:`isolator.numerics.dop853_driver`), in
worker threads: a pack whose runs share the staged inputs (the parameters the
inputs' staged form depends on: masses, inertia, carriage axes and origins)
steps the staged right-hand side on them; a pack whose runs differ there steps
the whole right-hand side on the inputs every run shares (the carriages'
motion), as fast; a pneumatic pack's steps end on every run's valve switches
(:mod:`isolator.simulation.valve_events`). Each pack's metrics come from its dense output as a single
run's do (:mod:`isolator.simulation.dense_metrics`), a pack's runs at once (in the compiled loop), and
whether a signal leaves its band after the run's end from the free motion
(:mod:`isolator.simulation.free_tail`).
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from isolator.errors import ParameterError, ScenarioError, SimulationError
from isolator.numerics.dop853 import DenseStepper, StepPlan
from isolator.numerics.native import vector_lanes
from isolator.scenario.arguments import check_public
from isolator.simulation.batch_setup import BatchSimulator, check_memory_of, solve_rests
from isolator.simulation.dense_metrics import DenseRuns, dense_metrics
from isolator.simulation.free_tail import FreeTail
from isolator.simulation.settling import Band, judged_times, signal_bands, still_signals
from isolator.simulation.stepping import (
    MAX_TURN,
    Method,
    check_turn,
    dense_stepper,
    hold_time,
    rk4_stepper,
    signal_width,
    stage_inputs,
    staged_parameters,
)
from isolator.simulation.tail_check import RunTails
from isolator.simulation.time_grid import inputs_at
from isolator.simulation.valve_events import ValveSwitches, step_on_switches

__all__ = ["BLOCK", "LANES", "STATUSES", "BatchResult", "BatchSimulator", "run_batch", "scale_label"]

#: runs per task of a worker thread (their metrics are computed together)
BLOCK = 16
#: runs stepped side by side in one compiled call (AVX-512 holds eight doubles, AVX four)
LANES = vector_lanes()
#: a run's status: measured, no stable rest or turned past ``MAX_TURN``, non-finite states, not run (it
#: would need far too many steps or more memory than the machine has), the run's work failed (a sweep's
#: chunk that failed twice)
STATUSES = ("ok", "tipped", "diverged", "refused", "failed")
#: a run may use at most this fraction of the memory available (1 / MEMORY_SHARE)
MEMORY_SHARE = 4

#: a simulator's cache of staged inputs is not shared between threads (batches may run side by side)
_STAGING = threading.Lock()
#: per simulator, the model's inputs at each step plan's stage times (packs of differing time-only parts)
_RAW: weakref.WeakKeyDictionary[BatchSimulator, dict[int, np.ndarray]] = weakref.WeakKeyDictionary()


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
        Why each failed run failed, by run index (with ``diverged="record"``).
    band : Band
        How the band was chosen (the scenario's ``[settling]`` rule unless given).
    half_widths : ndarray (runs, 6)
        The band each run's settling time is measured in [m or rad] (own bands: per run; NaN for a run
        that diverged).
    status : ndarray (runs,) of str
        One of :data:`STATUSES` per run (``reason`` gives the words of the others).
    unsettled : mapping of int to str
        Why a run measured ("ok") shows no settling time, by run index (its first signal without one).
    """

    settling_time: np.ndarray
    settling_time_max: np.ndarray
    peak: np.ndarray
    failures: Mapping[int, str] = field(default_factory=dict)
    band: Band = field(default_factory=Band)
    half_widths: np.ndarray = field(default_factory=lambda: np.zeros((0, 6)))
    status: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=object))
    unsettled: Mapping[int, str] = field(default_factory=dict)

    def run_band(self, i: int) -> Band:
        """The band of run ``i``, resolved (its six half-widths)."""
        return Band(self.band.kind, self.band.fraction, self.band.baseline,
                    tuple(float(v) for v in self.half_widths[i]))

    def reason(self, i: int) -> str:
        """Why run ``i`` has no metrics, or no settling time ('' for a run that settled)."""
        return self.failures.get(i, self.unsettled.get(i, ""))


def run_batch(
    sim: BatchSimulator,
    params: np.ndarray,
    workers: int = 2,
    progress: bool = False,
    diverged: Literal["raise", "record"] = "raise",
    band: Band | None = None,
    label: Callable[[int], str] = lambda i: f"run {i}",
) -> BatchResult:
    """Runs of ``sim``'s scenario, one per parameter vector.

    Parameters
    ----------
    sim : Simulator
        (or anything with what :class:`BatchSimulator` lists)
    params : ndarray (runs, parameters)
        Whole parameter vectors (``sim.layout.names``), already checked by their rules
        (:meth:`ParameterLayout.checked`, :meth:`ParameterLayout.with_changes`).
    workers : int
        Threads (the compiled stepping releases the GIL).
    progress : bool
        Print a progress line every 10 %.
    diverged : {"raise", "record"}
        A run that diverges (or turns the table past 0.2 rad), or whose table has no stable rest, stops
        the batch with :class:`SimulationError` / :class:`UnstableTableError` ("raise"), or gets NaN
        metrics, its status and its reason in ``BatchResult.failures`` ("record", for sweeps into soft
        designs).
    band : Band, optional
        The settling band (default: the scenario's ``[settling]`` rule).
    label : callable
        How a message names run ``i`` (default ``run i``; '' leaves the name out).

    Returns
    -------
    BatchResult
        The same metrics as :meth:`Simulator.run` gives for each run.

    Raises
    ------
    ParameterError
        ``params`` of the wrong shape, or ``diverged`` unknown.
    UnstableTableError
        A run's table has no stable equilibrium (the message names the run), with ``diverged="raise"``.
    SimulationError
        A run diverged (the message names the run), with ``diverged="raise"``.
    """
    if diverged not in ("raise", "record"):
        raise ParameterError(f"diverged: must be 'raise' or 'record', got {diverged!r}")
    params = np.asarray(params, dtype=float)
    if params.ndim != 2 or params.shape[1] != sim.layout.size:
        raise ParameterError(f"params: must be an array (runs, {sim.layout.size}) of parameter vectors, "
                             f"got shape {params.shape}")
    n = params.shape[0]
    rule = Band.from_settling(sim.scenario.settling) if band is None else band
    settling = np.full((n, 6), np.nan)
    peak = np.zeros((n, 6))
    status = np.full(n, "ok", dtype=object)
    failures: dict[int, str] = {}

    def failed(i: int, exc: Exception, kind: str) -> None:
        message = f"{label(i)}: {exc}" if label(i) else str(exc)
        if diverged == "raise":
            raise type(exc)(message) from None
        failures[i] = message
        status[i] = kind
        peak[i] = np.nan

    if n == 0:
        return BatchResult(settling, np.zeros(0), peak, {}, rule, np.zeros((0, 6)), status)
    starts, ends = solve_rests(sim, params, lambda i, exc: failed(i, exc, "tipped"))
    good = [i for i in range(n) if starts[i] is not None]
    methods: dict[int, Method] = {}
    for i in good:
        start, end = starts[i], ends[i]
        assert start is not None
        try:
            methods[i] = sim.method_for(max(start.max_frequency, end.max_frequency if end else 0.0))
        except ScenarioError as exc:  # far too many steps
            failed(i, exc, "refused")
    for method in {m.plan_key: m for m in methods.values()}.values():  # compiled before the threads start
        try:
            check_memory_of(sim, method, LANES, MEMORY_SHARE)
        except ParameterError as exc:
            for i in [i for i, m in methods.items() if m.plan_key == method.plan_key]:
                failed(i, exc, "refused")
                del methods[i]
            continue
        if method.plan is None:
            sim.grid_inputs(method.substeps)
            rk4_stepper(sim.model, method.substeps)
    stepper = dense_stepper(sim.model, LANES)
    width = signal_width(sim.model)
    uses = staged_parameters(sim.model)
    if len({params[i, uses].tobytes() for i in methods}) > 1:  # packs of differing time-only parts: compiled now
        dense_stepper(sim.model, LANES, staged=False)
    t = sim.grid.samples
    finals = np.zeros((n, 6))
    stops = any(e is not None for e in ends)
    if stops and good:
        finals[good] = sim.signals(np.array([ends[i].state for i in good]),  # type: ignore[union-attr]
                                   np.array([starts[i].state for i in good])).T  # type: ignore[union-attr]
    holds = np.array([hold_time(e) for e in ends])
    unsettled: dict[int, str] = {}

    def record(i: int, reasons: Sequence[str], times: np.ndarray) -> None:
        """Keep why run ``i`` shows no settling time (its first signal without one)."""
        why = next((r for r, t in zip(reasons, times, strict=True) if np.isnan(t)), "")
        if why:
            unsettled[i] = why
    lock = threading.Lock()
    done = [0]

    def pack(runs: list[int]) -> list[tuple[int, np.ndarray]]:
        """Step ``runs`` (one plan, at most LANES) side by side; their metrics. Runs with one time-only part
        share its staged inputs; others step the whole right-hand side on the inputs every run shares."""
        method = methods[runs[0]]
        full = method.plan
        assert full is not None
        plan = full.probes_only() if full.probes else full  # no output samples: not needed
        if len({params[i, uses].tobytes() for i in runs}) == 1:
            with _STAGING:
                inputs, steps = sim.plan_inputs(method, params[runs[0]]), stepper
        else:
            with _STAGING:
                raw = _RAW.setdefault(sim, {})  # the inputs at the plan's stage times, kept with the simulator
                if method.plan_key not in raw:
                    while len(raw) >= 16:  # the oldest plan's first
                        raw.pop(next(iter(raw)))
                    raw[method.plan_key] = np.ascontiguousarray(inputs_at(sim.scenario, *plan.stage_times()))
                inputs, steps = raw[method.plan_key], dense_stepper(sim.model, LANES, staged=False)
        lanes = runs + runs[-1:] * (LANES - len(runs))  # a short pack repeats its last run
        x0 = np.array([starts[i].state for i in lanes])  # type: ignore[union-attr]
        staged = steps is stepper

        def step(steps_plan: StepPlan) -> tuple[np.ndarray, ...]:
            at = inputs if steps_plan is plan else stage_inputs(sim.scenario, sim.model, steps_plan, params[runs[0]]) \
                if staged else np.ascontiguousarray(inputs_at(sim.scenario, *steps_plan.stage_times()))
            out, tops, deviations, polys = steps.run_slots(x0, steps_plan, at, params[lanes], x0, with_states=True,
                                                          final=finals[lanes])
            assert polys is not None  # with_states
            return out, tops, deviations, polys, at

        switches = [ValveSwitches.of(sim.scenario, sim.layout, params[i]) for i in runs]
        if any(s is not None for s in switches):  # every run's valve switches among the pack's step ends
            def replan(times: np.ndarray) -> StepPlan:
                nonlocal full
                full = sim.step_plan(method.plan_key, times)
                return full.probes_only() if full.probes else full
            plan, stepped = step_on_switches(switches, plan, step, lambda out: [out[3][..., lane] for lane in
                                                                                 range(len(runs))], replan)
        else:
            stepped = step(plan)
        slots, step_peaks, deviations, polys, inputs = stepped

        def samples(lane: int) -> np.ndarray:
            """The run's signals at the output samples after the first (steps again: only for a message)."""
            every = steps.run_slots(x0, full, inputs, params[lanes], x0, final=finals[lanes])[0]
            return every[full.sample_slots, :, lane]
        dense = DenseRuns(plan, slots, step_peaks, deviations, polys, x0, sim.model.variant.signals, width,
                          steps.driver)
        shape = polys.shape  # the states at the end, every lane at once (the same sums as one lane's)
        last = DenseStepper.states_at(plan, polys.reshape(*shape[:2], -1), np.array([plan.end]))[0]
        last = np.ascontiguousarray(last.reshape(shape[2:]).T[: len(runs)])
        tails = None  # pneumatic tables: their valves need each run's tail now; else judged per task
        if sim.scenario.is_pneumatic:
            tails = RunTails.of(sim.scenario, sim.model, params[runs], [starts[i] for i in runs],  # type: ignore[misc]
                                [ends[i] for i in runs], last, plan.end)
        has = tails.has if tails is not None else np.array(
            [ends[i] is not None and bool(np.all(np.isfinite(x))) for i, x in zip(runs, last, strict=True)])
        waits = np.array([0.0 if has[min(lane, len(runs) - 1)] else holds[i] for lane, i in enumerate(lanes)])
        tops, times, _ = dense_metrics(dense, finals[lanes] if stops else None, sim.stop_time, rule, waits)
        pending = []
        for lane, i in enumerate(runs):
            peak[i] = tops[lane]
            try:
                if not np.all(np.isfinite(peak[i])):
                    sig = samples(lane)
                    bad = np.argmax(~np.all(np.isfinite(sig), axis=1)) + 1
                    raise SimulationError(f"the run diverged: non-finite state at t = {t[bad]:.4g} s")
                check_turn(peak[i])
            except SimulationError as exc:
                failed(i, exc, "tipped" if np.nanmax(peak[i][3:], initial=0.0) > MAX_TURN else "diverged")
                continue
            settling[i] = np.where(still_signals(rule, peak[i]), 0.0, times[lane]) if stops else times[lane]
            if tails is not None and has[lane]:
                judge(i, *tails.get(lane))
            elif has[lane]:
                pending.append((i, last[lane]))
        return pending

    def judge(i: int, tail: FreeTail | None, note: str) -> None:
        """Run ``i``'s settling times by the verdict on its free motion after the end."""
        settling[i], reasons = judged_times(settling[i], np.zeros(6), peak[i], stops, rule, "", tail, note)
        record(i, reasons, settling[i])

    def judge_all(pending: list[tuple[int, np.ndarray]], end: float) -> None:
        """The runs of a task's packs (``(run, state at the end)``) by their free motions, decomposed side by
        side; a run's tail built only when the bound cannot show every signal inside (or a time is missing):
        else the verdict keeps every time as it is."""
        if not pending:
            return
        rows = [i for i, _ in pending]
        tails = RunTails.of(sim.scenario, sim.model, params[rows], [starts[i] for i in rows],  # type: ignore[misc]
                            [ends[i] for i in rows], np.array([x for _, x in pending]), end)
        inside = tails.inside(np.maximum(signal_bands(rule, peak[rows]), 1e-300))
        for k, i in enumerate(rows):
            if not (inside[k].all() and np.all(np.isfinite(settling[i]))):
                judge(i, *tails.get(k))

    def task(runs: list[int]) -> None:
        """A thread's share, runs of one method: RK4 runs one by one, DOP853 runs in packs."""
        method = methods[runs[0]]
        if method.plan is None:
            for i in runs:
                try:
                    metrics = sim.run_method(params[i], starts[i], ends[i], method,  # type: ignore[arg-type]
                                             band=rule).settling
                except SimulationError as exc:
                    failed(i, exc, "diverged")
                    continue
                settling[i] = [np.nan if r.time is None else r.time for r in metrics.values()]
                peak[i] = [r.peak for r in metrics.values()]
                record(i, [r.reason for r in metrics.values()], settling[i])
        else:
            pending = [item for lo in range(0, len(runs), LANES) for item in pack(runs[lo : lo + LANES])]
            judge_all(pending, method.plan.end)
        with lock:
            done[0] += len(runs)
            if progress and n >= 10 and (done[0] * 10) // n != ((done[0] - len(runs)) * 10) // n:
                print(f"  batch: {done[0]}/{n} runs", flush=True)

    if workers <= 1:  # in this thread (a sweep's worker process)
        list(map(task, _tasks(sim, params, methods)))
    else:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(task, _tasks(sim, params, methods)))
    with np.errstate(all="ignore"):
        worst = np.where(np.all(np.isfinite(settling), axis=1), np.max(settling, axis=1), np.nan)
    return BatchResult(settling, worst, peak, dict(sorted(failures.items())), rule, rule.resolve(peak), status,
                       dict(sorted(unsettled.items())))


def _tasks(sim: BatchSimulator, params: np.ndarray, methods: Mapping[int, Method]) -> list[list[int]]:
    """Runs of one plan next to each other, whole packs of one time-only part (one staged input) first and
    the rest after them, mixed (their packs step the whole right-hand side); tasks of ``BLOCK`` runs."""
    uses = staged_parameters(sim.model)
    groups: dict[tuple[int, int], dict[bytes, list[int]]] = {}
    for i, method in methods.items():
        staged = params[i, uses].tobytes() if method.plan is not None else b""
        kind = (method.plan_key, -1 if method.plan is not None else method.substeps)  # RK4: by its substeps
        groups.setdefault(kind, {}).setdefault(staged, []).append(i)
    tasks = []
    for _, same in sorted(groups.items()):
        whole = [i for members in same.values() for i in members[: len(members) - len(members) % LANES]]
        order = whole + [i for members in same.values() for i in members[len(members) - len(members) % LANES :]]
        tasks += [order[lo : lo + BLOCK] for lo in range(0, len(order), BLOCK)]
    return tasks


def scale_label(stiffness: Sequence[float] | float, damping: Sequence[float] | float) -> Callable[[int], str]:
    """How a batch of scaled designs names run ``i``: ``run i (stiffness x1.2, damping x0.5)``."""
    k, c = np.asarray(stiffness, dtype=float).reshape(-1), np.asarray(damping, dtype=float).reshape(-1)
    return lambda i: f"run {i} (stiffness x{k[i]:g}, damping x{c[i]:g})"


check_public(globals(), ("BatchResult"))
