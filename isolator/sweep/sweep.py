"""``sweep``: many designs of one scenario, run on any :class:`concurrent.futures.Executor`."""

from __future__ import annotations

import contextlib
import math
import os
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import Executor
from pathlib import Path
from typing import Any, Literal

import numpy as np

from isolator.errors import ExecutorError, ParameterError
from isolator.model.parameters import ParameterLayout
from isolator.scenario.definitions import Scenario
from isolator.scenario.reader import load_scenario
from isolator.simulation.settling import Band
from isolator.sweep import output
from isolator.sweep.budget import budget_columns, budget_requests
from isolator.sweep.cluster import connect
from isolator.sweep.designs import Designs, Values, build_designs
from isolator.sweep.metrics import metric_columns
from isolator.sweep.names import joint_entries
from isolator.sweep.output import RowSink, column_names, staging_path
from isolator.sweep.pool import SweepPool
from isolator.sweep.progress import progress_bar, worker_notice
from isolator.sweep.result import SweepResult, Tally
from isolator.sweep.runner import run_chunks
from isolator.sweep.worker import (
    TRANSMISSIBILITY_AXES,
    Chunk,
    ChunkResult,
    checked_frequencies,
    scenario_key,
    simulator_for,
)

__all__ = ["MAX_CHUNK", "WORKERS_PER_CORE", "check_workers", "chunk_size_for", "default_workers", "sweep"]

#: designs per chunk at most (about 0.3 s of work on one core for Table 3.2: a Dask task costs some 10 ms)
MAX_CHUNK = 512
#: local worker processes per core at most (more only share the cores, each with its own memory)
WORKERS_PER_CORE = 4


def default_workers() -> int:
    """Worker processes of the default pool: the cores this process may use.

    Returns
    -------
    int
        The number of cores this process may use (its CPU affinity where the system has one), >= 1.
    """
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def check_workers(value: object, name: str = "workers") -> int:
    """A count of local worker processes: a whole number from 1 to :data:`WORKERS_PER_CORE` times the cores
    (:func:`default_workers`); else a :class:`ParameterError` naming ``name``."""
    workers, most = _positive(value, name), WORKERS_PER_CORE * default_workers()
    if workers > most:
        raise ParameterError(f"{name}: {workers} worker processes on {default_workers()} core(s); at most {most} "
                             f"({WORKERS_PER_CORE} per core: more would only share the cores and the memory)")
    return workers


def chunk_size_for(designs: int, workers: int) -> int:
    """Designs per chunk: about four chunks per worker (every worker gets work when there are at least as
    many designs as workers), at most :data:`MAX_CHUNK`.

    Parameters
    ----------
    designs : int
        Number of designs.
    workers : int
        Number of workers.

    Returns
    -------
    int
        Designs per chunk, >= 1.
    """
    return max(1, min(MAX_CHUNK, math.ceil(designs / (4 * max(1, workers)))))


def sweep(
    scenario: Scenario | str | Path | None,
    set: Mapping[str, Values] | None = None,
    scale: Mapping[str, Values] | None = None,
    *,
    zip: bool = False,
    samples: int | None = None,
    method: Literal["sobol", "lhs"] = "sobol",
    seed: int = 0,
    model: str = "exact",
    executor: Executor | Callable[[], Executor] | None = None,
    workers: int | None = None,
    frequencies: Sequence[float] = (),
    modes: bool = False,
    budget: Sequence[str] | str | None = None,
    out: str | Path | None = None,
    resume: bool = False,
    force: bool = False,
    progress: bool = False,
    chunk_size: int | None = None,
    band: Band | None = None,
    scheduler: str | None = None,
    security: Any = None,
) -> SweepResult:
    """Run a scenario for many designs; per design the settling times, peaks and status.

    Parameters
    ----------
    scenario : Scenario, str or Path
        A scenario, a file or a bundled name (None: the default scenario).
    set : mapping of str to values, optional
        Parameter name (``Simulator(...).layout.names``; ``[*]`` for every element,
        ``isolators[*].stiffness.z``; a vector's name for all its components, ``isolators[0].damping``)
        to absolute values [SI units]: a list (crossed with the others into a grid, first name outermost;
        with ``zip``, paired), or with ``samples`` a range ``(low, high)``.
    scale : mapping of str to values, optional
        The same, as factors [-] on the scenario's values.
    zip : bool
        Pair the lists (one length) instead of crossing them.
    samples : int, optional
        Draw this many designs over the ranges, by ``method``: "sobol" (scrambled) or "lhs" (Latin
        hypercube), seeded by ``seed`` (reproducible).
    model : {"exact", "paper"}
    executor : concurrent.futures.Executor or callable, optional
        Where the chunks run: any executor (a Dask ``Client.get_executor()``, mpi4py's
        ``MPIPoolExecutor``), or a function of no arguments making one (``MPIPoolExecutor``), which the sweep
        calls again for a fresh executor when one breaks (``BrokenExecutor``), as it renews its own pool; default
        a local process pool of ``workers`` processes whose workers end with the sweep
        (:mod:`isolator.sweep.pool`).
    workers : int, optional
        Processes of the default pool (default: the machine's cores; 1: in this process, one chunk after
        another); with ``executor``, how many workers it has (sizes the chunks; default its own count).
    frequencies : sequence of float
        [Hz]: per design the same-axis transmissibility magnitudes (floor x, y, z to table x, y, z, about
        the rest with the carriages at their start) at each, columns ``transmissibility:<axis>@<f>Hz``.
    modes : bool
        Per design the six (spring-dampers) mode frequencies [Hz], columns ``mode:1`` ... ``mode:6``.
    budget : sequence of str, optional
        ``"point:axis"`` entries (``[[points]]`` names, or ``table``, the mass centre, without points; axes x,
        y, z), or one string of them separated by commas: per design the passive error budget's displacement
        RMS [m] there, columns ``budget:<point>:<axis>``:
        :func:`~isolator.analysis.budget.error_budget` of ``linearise(scenario, parameters=p)`` (the design's
        table parked with its carriages at their start), default band (0.1 Hz to 1 kHz). The scenario needs a
        random source (``[ground.spectrum]``, ``[[disturbances]]`` or an actuator's ``noise_psd``).
    out : str or Path, optional
        Write the rows as they arrive, ``.csv`` or ``.parquet`` (needs pyarrow); the result then reads
        its columns back from the file (memory flat in the number of designs).
    resume : bool
        Continue the sweep whose rows ``out`` holds (designs already there are skipped). A sweep describes
        itself beside ``out`` in ``<out>.sweep.json`` when it starts: the :func:`~isolator.sweep.worker.scenario_key`
        hash of the scenario and model, the model, the band (:meth:`Band.to_dict`, null: the scenario's
        rule), the sampling (``samples``, ``method`` and ``seed`` when sampled, ``zip``), ``frequencies``,
        ``modes`` and ``budget`` (when asked for); a resume that differs in any is refused, naming what differs
        (a file without the description, from an older version, is resumed as it is). The file's columns and
        each row's swept values must also be this sweep's.
    force : bool
        Overwrite ``out`` and its description (without ``resume`` or ``force`` an existing ``out`` is an
        error).
    progress : bool
        Show how far the sweep has got on stderr once it has run 2 s: a bar on a terminal, else a line per
        tenth of the designs (:mod:`isolator.sweep.progress`).
    chunk_size : int, optional
        Designs per task (default :func:`chunk_size_for`).
    band : Band, optional
        The settling band (default the scenario's ``[settling]`` rule).
    scheduler : str, optional
        Run on the Dask cluster of this scheduler (instead of ``executor``): ``tls://HOST:PORT`` with
        ``security``, or ``tcp://HOST:PORT`` (warned about beyond this machine: anyone who reaches it runs code
        on its workers); see :func:`isolator.sweep.cluster.connect`.
    security : distributed.Security, optional
        The TLS certificates of a ``tls://`` scheduler (:func:`isolator.sweep.cluster.tls_security` makes one
        from the three files; default Dask's configuration).

    Returns
    -------
    SweepResult
        Columns in design order: one per swept name as given (a scale column holds the factor),
        ``settling_time_max`` [s], ``settling:<signal>`` [s], ``peak:<signal>`` [m or rad], ``status``
        ("ok", "tipped": no stable rest or turned past 0.2 rad, "diverged", "refused": it would need far too
        many steps or too much memory, "invalid": the design breaks a rule of its parameters, "unsettled": no
        settling time within the run, the signals named in ``reason``, or a step of the ``[sequence]`` that did not
        settle, "failed": its chunk failed twice),
        ``reason``, ``design``, ``band:<signal>`` (the half-widths [m or rad] the settling time is measured in,
        as ``--band`` takes them), the scenario's kind's columns, the transmissibility, mode and budget columns.

        A pneumatic scenario, one with ``[[windows]]`` or with a ``[sequence]`` runs each design on its own
        (``Simulator.run_method`` from its equilibria, or ``run_sequence(..., parameters=p)``), and adds:

        * pneumatic: ``dynamic_settling_time_max`` [s] (the settling about the slowly leveling table),
          ``leveling_time`` [s] (the largest over the valve groups; NaN when one is not level by the end),
          ``supply_exhausted`` (1 when a group wanted air at its supply pressure, else 0);
        * ``[[windows]]`` (a single move): ``window_settling_time_max`` [s] (after the stop) and
          ``moves_per_hour`` [1/h], ``3600 / (move time + window settling time)`` (the move time from the
          first carriage's start to the stop);
        * ``[sequence]`` (instead of the two above): ``total_time`` [s] (first step's start to last step's
          end), ``throughput_per_hour`` [1/h] (steps per hour) and ``unsettled_step`` (NaN when every step
          settled); the 5 % settling, peak and band columns are NaN.

    Raises
    ------
    ParameterError
        A bad argument, named; nothing is written then.
    ScenarioError
        ``budget`` on a scenario without a random source.
    ExecutorError
        The executor could no longer run the chunks (a Dask scheduler that is gone): the rows written to
        ``out`` are kept, ``resume=True`` finishes the sweep. A worker process of the default pool that dies
        is no error: the pool is renewed (one warning) and every row is kept.

    Examples
    --------
    >>> from isolator.sweep import sweep
    >>> result = sweep("paper-table-3-2", scale={"isolators[*].damping": [0.5, 1, 2]}, workers=1)
    >>> result["settling_time_max"].round(2).tolist()  # the least damped design does not settle within the run
    [nan, 2.31, 1.14]
    >>> result.best()["isolators[*].damping"]
    2.0
    """
    start_time = time.perf_counter()
    if scheduler is not None and executor is not None:
        raise ParameterError("scheduler, executor: choose one (the scheduler's cluster runs the chunks)")
    if security is not None and scheduler is None:
        raise ParameterError("security: the certificates of a tls:// scheduler: give scheduler= too")
    scene = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    layout = ParameterLayout.of(scene)
    designs = build_designs(layout, layout.pack(scene), set, scale, zip, samples, method, seed)
    freqs, n_modes = checked_frequencies(frequencies), 6 if modes else 0
    requests = budget_requests(scene, budget)
    metrics = metric_columns(scene)
    best_by = "total_time" if "total_time" in metrics else "settling_time_max"  # a sequence: finished first
    columns = column_names(designs.names, freqs, TRANSMISSIBILITY_AXES, n_modes, metrics, budget_columns(requests))
    path, key = None if out is None else Path(out), scenario_key(scene, model)
    identity: dict[str, Any] = {"scenario_key": key, "model": model, "band": None if band is None else band.to_dict(),
                                "samples": samples, "method": None if samples is None else method,
                                "seed": None if samples is None else seed, "zip": zip, "frequencies": freqs,
                                "modes": n_modes}
    identity |= {"budget": budget_columns(requests)} if requests else {}  # else as sweeps without budget were
    done, on_disk = output.prepared(path, resume, force, identity, columns, designs.names, designs.values,
                                    best_by, designs.count)
    tally = Tally(designs.count, int(np.sum(done)), column=best_by, metric=metrics.index(best_by) if best_by in metrics
                  else None)
    if tally.resumed and on_disk is not None:  # the rows a resume found
        tally.count(on_disk["design"].astype(int), on_disk[tally.column], on_disk["status"])
        if path is not None and not staging_path(path).exists():  # a finished .parquet
            if not done.all():
                raise ParameterError(f"out: '{path}' is a finished sweep of other designs; force=True starts again")
            return SweepResult.made(columns, designs.names, path, None, tally, time.perf_counter() - start_time,
                                    designs.scaled)
    with contextlib.ExitStack() as cluster:
        if scheduler is not None:  # connected once the arguments are known good, before anything is written
            client = connect(scheduler, security)
            cluster.callback(_close, client)
            executor = client.get_executor()
        n_workers = _workers(workers, executor)
        size = chunk_size_for(int(np.sum(~done)), n_workers) if chunk_size is None else _positive(chunk_size)
        swept = {i: f"{c.mode}[{c.name!r}]" for c in designs.columns for i in joint_entries(layout) & {*c.entries}}
        template = Chunk(key, scene, model, 0, np.zeros((0, layout.size)), tuple(swept), band, freqs, n_modes,
                         budget=requests, labels=tuple(swept.values()))
        simulator_for(template)  # the scenario checked before anything is written; the forked workers inherit it
        chunks = _chunk_count(done, size)  # no more processes than chunks to run
        pool, renew = _executor(executor, n_workers, min(n_workers, chunks))  # made (a function's executor checked)
        if pool is not None and renew is not None:  # should the sweep fail before its chunks run (else a no-op)
            cluster.callback(pool.shutdown, wait=False, cancel_futures=True)
        if path is not None:
            output.write_sidecar(path, identity)
        sink = None if path is None else RowSink(path, columns, append=resume)
        if path is not None and path.suffix.lower() == ".parquet" and force and path.exists():
            path.unlink()
        rows: list[list[Any]] | None = [] if sink is None else None

        def finished(result: ChunkResult) -> None:
            block = _rows(designs, result)
            tally.add(result)
            if sink is not None:
                sink.write(block)
            elif rows is not None:
                rows.extend(block)
            bar(len(block))

        bar = progress_bar(progress, designs.count, int(np.sum(done)))
        complete = False
        try:
            run_chunks(_chunks(designs, template, done, size), pool, 2 * n_workers + 1, finished, renew,
                       _alive(pool, worker_notice(progress)))
            complete = True
        except ExecutorError as exc:
            kept = f"the {tally.resumed + tally.runs} rows done are kept in '{path}'" if path is not None else \
                "the rows are lost (out= keeps them as they arrive)"
            raise ExecutorError(f"{exc}; {kept}: run the same sweep with resume=True to finish it") from None
        finally:
            if sink is not None:
                sink.close(complete)
            bar(-1)
        return SweepResult.made(columns, designs.names, path, rows, tally, time.perf_counter() - start_time,
                                designs.scaled)


def _rows(designs: Designs, result: ChunkResult) -> list[list[Any]]:
    """A chunk's rows, one value per column."""
    out = []
    for r in range(result.status.size):
        i = result.start + r
        with np.errstate(all="ignore"):
            worst = float(np.max(result.settling[r])) if np.all(np.isfinite(result.settling[r])) else math.nan
        out.append([*map(float, designs.values[i]), worst, *map(float, result.settling[r]),
                    *map(float, result.peak[r]), str(result.status[r]), " ".join(str(result.reason[r]).split()), i,
                    *map(float, result.band[r]), *map(float, result.metrics[r]), *map(float, result.extras[r])])
    return out


def _chunks(designs: Designs, template: Chunk, done: np.ndarray, size: int) -> Iterator[Chunk]:
    """The chunks of the designs not done yet, each of consecutive designs, made when needed."""
    from dataclasses import replace

    todo = np.flatnonzero(~done)
    lo = 0
    while lo < todo.size:  # a run of consecutive designs, at most ``size``
        start = int(todo[lo])
        hi = lo + 1
        while hi < todo.size and hi - lo < size and todo[hi] == todo[hi - 1] + 1:
            hi += 1
        yield replace(template, start=start, params=designs.parameters(start, start + hi - lo))
        lo = hi


def _chunk_count(done: np.ndarray, size: int) -> int:
    """How many chunks :func:`_chunks` makes of the designs not done."""
    todo = np.flatnonzero(~done)
    runs = np.split(todo, np.flatnonzero(np.diff(todo) != 1) + 1) if todo.size else []
    return sum(-(-run.size // size) for run in runs)


def _executor(executor: Executor | Callable[[], Executor] | None, workers: int,
              processes: int) -> tuple[Executor | None, Callable[[], Executor] | None]:
    """The executor and how to make a fresh one (the pool made here, of ``processes`` workers, or the caller's
    function making one)."""
    if isinstance(executor, Executor):
        return executor, None
    if executor is not None:
        if not callable(executor):
            raise ParameterError(f"executor: must be a concurrent.futures.Executor or a function making one, got "
                                 f"{type(executor).__name__}")
        made = executor()
        if not isinstance(made, Executor):
            raise ParameterError(f"executor: the function must return a concurrent.futures.Executor, got "
                                 f"{type(made).__name__}")
        return made, executor
    if workers <= 1:
        return None, None

    def make() -> Executor:
        return SweepPool(max(1, processes))

    return make(), make


def _close(client: Any) -> None:
    """Close a Dask client the sweep opened (quietly: its scheduler may be gone)."""
    with contextlib.suppress(Exception):
        client.close(timeout=2)


def _alive(executor: Executor | None, notice: Callable[[Any], None]) -> Callable[[], bool] | None:
    """Whether a Dask executor's client still talks to its scheduler (None: an executor that cannot tell);
    ``notice`` is told of the client each time (a cluster without workers, said once)."""
    client = getattr(executor, "_client", None)
    if client is None or not hasattr(client, "status"):
        return None

    def alive() -> bool:
        notice(client)
        return str(client.status) in ("running", "connecting", "newly-created")

    return alive


def _workers(workers: int | None, executor: Executor | Callable[[], Executor] | None) -> int:
    if workers is not None:
        return _positive(workers, "workers") if executor is not None else check_workers(workers)
    if executor is not None:  # a pool's own count, a Dask cluster's threads, else this machine's cores
        client = getattr(executor, "_client", None)
        if client is not None and hasattr(client, "nthreads"):
            return max(1, sum(client.nthreads().values()))
        return int(getattr(executor, "_max_workers", 0) or default_workers())
    return default_workers()


def _positive(value: object, name: str = "chunk_size") -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ParameterError(f"{name}: must be a whole number >= 1, got {value!r}")
    return int(value)

