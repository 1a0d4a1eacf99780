"""A chunk of a sweep, run where an executor puts it: the worker builds the scenario's
:class:`~isolator.simulation.simulator.Simulator` once (a module-level cache keyed by a hash of the
scenario and model) and reuses it for every chunk it gets."""

from __future__ import annotations

import ctypes
import hashlib
import math
import pickle
import sys
import threading
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from isolator.analysis.linear import linearise
from isolator.analysis.modes import modes
from isolator.errors import IsolatorError, ParameterError
from isolator.scenario.definitions import SIGNALS, Scenario
from isolator.simulation.batch import run_batch
from isolator.simulation.settling import Band, unavailable_reason
from isolator.simulation.simulator import Simulator
from isolator.sweep.budget import budget_values
from isolator.sweep.metrics import Runs, metric_columns, run_each, run_each_sequence, runs_alone

__all__ = ["TRANSMISSIBILITY_AXES", "Chunk", "ChunkResult", "checked_frequencies", "run_chunk", "scenario_key",
           "simulator_for", "unsettled_reason"]

#: the same-axis transmissibilities reported at each ``frequencies`` entry (floor motion to table motion)
TRANSMISSIBILITY_AXES = ("x", "y", "z")

_SIMULATORS: dict[str, Simulator] = {}
_BUILDING = threading.Lock()


def scenario_key(scenario: Scenario, model: str) -> str:
    """A hash of a scenario and model: which simulator a worker reuses."""
    return hashlib.sha256(pickle.dumps((scenario, model))).hexdigest()


@dataclass(frozen=True)
class Chunk:
    """Designs ``start`` to ``start + len(params) - 1`` of a sweep, as one task (picklable).

    Attributes
    ----------
    key : str
        :func:`scenario_key` of ``scenario`` and ``model``.
    scenario : Scenario
    model : str
    start : int
        The first design's index.
    params : ndarray (designs, parameters)
    check : tuple of int
        Entries whose designs are checked whole (:func:`isolator.sweep.names.joint_entries`), if swept.
    band : Band or None
        The settling band (None: the scenario's rule).
    frequencies : tuple of float
        [Hz] for the transmissibility columns.
    modes : int
        Mode frequencies to report (0: none).
    threads : int
        Threads of the batch inside the worker.
    budget : tuple of (str, str)
        (point, axis) pairs of the passive error budget's displacement RMS columns
        (:func:`isolator.sweep.budget.budget_requests`).
    labels : tuple of str
        How the sweep's caller named what drives each entry of ``check`` (``set['isolators[*].position.x']``),
        for the reason of a design refused whole (default: the entry's own name).
    """

    key: str
    scenario: Scenario
    model: str
    start: int
    params: np.ndarray
    check: tuple[int, ...] = ()
    band: Band | None = None
    frequencies: tuple[float, ...] = ()
    modes: int = 0
    threads: int = 1
    budget: tuple[tuple[str, str], ...] = ()
    labels: tuple[str, ...] = ()


@dataclass(frozen=True)
class ChunkResult:
    """The metrics of a chunk's designs.

    Attributes
    ----------
    start : int
    settling : ndarray (designs, 6)
        [s]; NaN where unavailable.
    peak : ndarray (designs, 6)
        [m or rad].
    status, reason : ndarray (designs,) of str
    extras : ndarray (designs, k)
        Transmissibility magnitudes [-] (each frequency: x, y, z), then mode frequencies [Hz], then the
        budget's RMS values [m].
    band : ndarray (designs, 6)
        The half-widths of the band each design's settling time is measured in [m or rad]; NaN: no run.
    metrics : ndarray (designs, len(metric_columns(scenario)))
        The columns of :func:`isolator.sweep.metrics.metric_columns`.
    """

    start: int
    settling: np.ndarray
    peak: np.ndarray
    status: np.ndarray
    reason: np.ndarray
    extras: np.ndarray
    band: np.ndarray
    metrics: np.ndarray


def simulator_for(chunk: Chunk) -> Simulator:
    """The worker's simulator of the chunk's scenario, built on first use."""
    with _BUILDING:  # one build per worker process, whichever of its threads asks first
        if not _SIMULATORS:
            keep_freed_memory()
        if chunk.key not in _SIMULATORS:
            if len(_SIMULATORS) >= 4:
                _SIMULATORS.pop(next(iter(_SIMULATORS)))
            _SIMULATORS[chunk.key] = Simulator(chunk.scenario, chunk.model)
        return _SIMULATORS[chunk.key]


def keep_freed_memory() -> None:
    """Let glibc's allocator keep large freed blocks (a run's arrays are megabytes, allocated per pack).

    Dask workers start with ``MALLOC_TRIM_THRESHOLD_`` set, which fixes the threshold above which
    glibc maps each allocation afresh: every pack then faults its pages in again, and a chunk takes
    2-3 times as long. Fixed thresholds of 32 MB (mapping) and 128 MB (trimming) restore the speed; a
    no-op where the C library is not glibc.
    """
    if not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(-3, 32 * 2**20)  # M_MMAP_THRESHOLD
        libc.mallopt(-1, 128 * 2**20)  # M_TRIM_THRESHOLD
    except (OSError, AttributeError):  # another C library
        return


def run_chunk(chunk: Chunk) -> ChunkResult:
    """Run a chunk's designs: a batch (tipped and diverged runs recorded), or each design on its own when the
    scenario is pneumatic, has windows or a sequence (:mod:`isolator.sweep.metrics`); the linear extras of each
    design that stands, designs whose swept entries break a joint rule recorded "invalid", and designs that ran
    without a settling time (a signal not settled by the run's end, a carriage that never stops) "unsettled",
    the reason saying which signals and why."""
    sim = simulator_for(chunk)
    n = chunk.params.shape[0]
    status = np.full(n, "ok", dtype=object)
    reason = np.full(n, "", dtype=object)
    if chunk.check:
        label = dict(zip(chunk.check, chunk.labels, strict=False))  # what the user typed, not isolators[0]
        for r, p in enumerate(chunk.params):
            try:
                sim.layout.check(p, lambda i: label.get(i, sim.layout.names[i]), chunk.check)
            except IsolatorError as exc:
                status[r], reason[r] = "invalid", str(exc)
    valid = np.flatnonzero(status == "ok")
    columns = metric_columns(chunk.scenario)
    settling, peak, band = np.full((n, 6), np.nan), np.full((n, 6), np.nan), np.full((n, 6), np.nan)
    metrics = np.full((n, len(columns)), np.nan)
    if runs_alone(chunk.scenario):
        runs: Runs = (run_each_sequence(chunk.scenario, chunk.model, chunk.params[valid])
                      if chunk.scenario.sequence is not None else run_each(sim, chunk.params[valid], chunk.band))
        settling[valid], peak[valid], band[valid], metrics[valid] = runs.settling, runs.peak, runs.half_widths, \
            runs.metrics
        status[valid], reason[valid] = runs.status, runs.reason
    else:
        batch = run_batch(sim, chunk.params[valid], chunk.threads, diverged="record", band=chunk.band,
                          label=lambda i: "")
        settling[valid], peak[valid], band[valid] = batch.settling_time, batch.peak, batch.half_widths
        status[valid] = batch.status
        for i, why in batch.failures.items():
            reason[valid[i]] = why
    if chunk.scenario.sequence is None:  # a sequence's own "unsettled" names its step
        for row in np.flatnonzero((status == "ok") & np.any(np.isnan(settling), axis=1)):
            status[row], reason[row] = "unsettled", unsettled_reason(sim, settling[row])
    width = len(chunk.frequencies) * len(TRANSMISSIBILITY_AXES) + chunk.modes + len(chunk.budget)
    extras = np.full((n, width), np.nan)
    if width:
        for row in np.flatnonzero((status != "invalid") & (status != "tipped")):
            extras[row] = _linear(sim.scenario, chunk.params[row], chunk.frequencies, chunk.modes, chunk.budget)
    return ChunkResult(chunk.start, settling, peak, status, reason, extras, band, metrics)


def unsettled_reason(sim: Simulator, settling: np.ndarray) -> str:
    """Why a design that ran has no settling time: no stop within the run, or the signals (NaN in
    ``settling`` [s]) not settled in the band before the run ends."""
    end = float(sim.scenario.simulation.duration)
    why = unavailable_reason(end, sim.stop_time)
    if why:
        return f"no settling time: {why}"
    late = ", ".join(s for s, t in zip(SIGNALS, settling, strict=True) if np.isnan(t))
    return (f"no settling time: {late} not settled in the band by the run's end at {end:g} s "
            "([simulation] duration)")


def _linear(scenario: Scenario, p: np.ndarray, frequencies: tuple[float, ...], count: int,
            budget: tuple[tuple[str, str], ...] = ()) -> np.ndarray:
    """Same-axis transmissibility magnitudes at ``frequencies``, the first ``count`` mode frequencies
    [Hz] (NaN past the modes there are) and the passive budget's RMS [m] at each ``budget`` (point, axis) of one
    design, about its rest with the carriages at their start."""
    try:
        lin = linearise(scenario, parameters=p)
    except IsolatorError:
        return np.full(len(frequencies) * len(TRANSMISSIBILITY_AXES) + count + len(budget), np.nan)
    out: list[float] = []
    if frequencies:
        axes = list(TRANSMISSIBILITY_AXES)
        h = lin.frequency_response(np.array(frequencies), [f"ground:{a}" for a in axes], axes)
        out += [float(v) for v in np.abs(np.diagonal(h, axis1=1, axis2=2)).ravel()]
    if count:
        found = modes(lin).frequencies_hz[:count]
        out += [*map(float, found), *[np.nan] * (count - found.size)]
    return np.array(out + budget_values(lin, budget))


def checked_frequencies(values: Sequence[float]) -> tuple[float, ...]:
    """The transmissibility columns' frequencies [Hz] of a sweep, each finite and >= 0 (else a
    :class:`ParameterError` naming ``frequencies``)."""
    try:
        out = tuple(float(f) for f in np.atleast_1d(np.asarray(values, dtype=float)))
    except (TypeError, ValueError):
        raise ParameterError(f"frequencies: must be numbers [Hz], got {values!r}") from None
    bad = [f for f in out if not (math.isfinite(f) and f >= 0)]
    if bad:
        raise ParameterError(f"frequencies: must be finite and >= 0 [Hz], got {bad[0]:g}")
    return out
