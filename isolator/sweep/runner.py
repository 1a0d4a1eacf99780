"""Chunks out to an executor, results back in design order: a bounded number in flight (memory flat),
a chunk that fails (its worker died, or it raised) retried once, then its rows recorded "failed".

When the sweep's own process pool breaks (a worker killed, out of memory, a crash in compiled code), found
by a chunk's result or by a submission the broken pool refuses, the pool is renewed and the sweep goes on
(one warning): which of the chunks in flight killed it is unknown, so each of them is run again alone (one
at a time), without charging it an attempt; a chunk that breaks the pool while it runs alone is the culprit:
that counts as its attempt. Once the suspects are cleared the chunks are handed out as before.

An executor the sweep cannot renew (a user's: Dask, MPI, threads) that refuses work (broken, shut down) or
drops it (a Dask scheduler that is gone cancels every task), or a pool that keeps breaking without finishing
a chunk, ends the sweep with an :class:`~isolator.errors.ExecutorError`: the rows given to ``done`` are
kept, and the sweep continues with ``resume``."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, BrokenExecutor, Executor, Future, wait

import numpy as np

from isolator.errors import ExecutorError
from isolator.sweep import worker
from isolator.sweep.metrics import metric_columns
from isolator.sweep.worker import Chunk, ChunkResult

__all__ = ["ATTEMPTS", "BROKEN_POOL_WARNING", "MAX_BREAKS", "POLL", "failed_result", "run_chunks"]

#: tries of a chunk before its rows are recorded "failed"
ATTEMPTS = 2
#: breaks of the sweep's pool in a row, without a chunk finished in between, before the sweep gives up
MAX_BREAKS = 5
#: how often [s] the runner asks ``alive`` while no chunk finishes
POLL = 1.0
#: the warning (one per sweep) when the sweep's pool broke and was renewed
BROKEN_POOL_WARNING = ("a worker process of the sweep died (killed, out of memory, or a crash): the sweep "
                       "renewed its pool and ran the chunks in flight again")


def failed_result(chunk: Chunk, exc: BaseException) -> ChunkResult:
    """The rows of a chunk that failed every attempt: status "failed", the reason the last error."""
    n = chunk.params.shape[0]
    died = isinstance(exc, BrokenExecutor)
    why = f"the worker died ({type(exc).__name__}: {exc})" if died else f"{type(exc).__name__}: {exc}"
    width = len(chunk.frequencies) * len(worker.TRANSMISSIBILITY_AXES) + chunk.modes
    return ChunkResult(chunk.start, np.full((n, 6), np.nan), np.full((n, 6), np.nan),
                       np.full(n, "failed", dtype=object), np.full(n, f"after {ATTEMPTS} attempts: {why}",
                                                                   dtype=object), np.full((n, width), np.nan),
                       np.full((n, 6), np.nan), np.full((n, len(metric_columns(chunk.scenario))), np.nan))


def run_chunks(
    chunks: Iterator[Chunk],
    executor: Executor | None,
    in_flight: int,
    done: Callable[[ChunkResult], None],
    renew: Callable[[], Executor] | None = None,
    alive: Callable[[], bool] | None = None,
) -> None:
    """Run every chunk and give ``done`` each result in the chunks' order.

    Parameters
    ----------
    chunks : iterator of Chunk
        In design order, made as they are needed.
    executor : Executor or None
        None: in this process, one chunk after another.
    in_flight : int
        Chunks submitted and not yet given to ``done``, at most.
    done : callable
        Called with each chunk's result, in order.
    renew : callable, optional
        A fresh executor when the current one broke (a process pool whose worker died): the chunks that
        were in flight then run again alone, uncharged (see the module's description); the old one is
        stopped with its ``stop()`` method if it has one. None: the executor is the caller's; a chunk whose
        future broke is retried like one that raised, and an executor that refuses or drops work ends the
        sweep.
    alive : callable, optional
        Asked every :data:`POLL` s while no chunk finishes: False (a Dask client that has closed) ends the
        sweep rather than wait for results that will not come.

    Raises
    ------
    ExecutorError
        The executor can no longer run the chunks (see the module's description).
    """
    if executor is None:
        for chunk in chunks:
            done(_serial(chunk))
        return
    _Flight(chunks, executor, in_flight, done, renew, alive).run()


class _Flight:
    """The chunks in flight on one executor (renewed when it breaks), and the results waiting for their turn."""

    def __init__(self, chunks: Iterator[Chunk], executor: Executor, in_flight: int,
                 done: Callable[[ChunkResult], None], renew: Callable[[], Executor] | None,
                 alive: Callable[[], bool] | None) -> None:
        self.chunks, self.pool, self.in_flight, self.done = chunks, executor, in_flight, done
        self.renew, self.alive = renew, alive
        self.pending: dict[Future[ChunkResult], tuple[Chunk, int, bool]] = {}  # chunk, attempt, run alone
        self.ready: dict[int, ChunkResult] = {}
        self.order: list[int] = []
        self.suspects: list[tuple[Chunk, int]] = []  # in flight when the pool broke: each to run alone
        self.queue: list[tuple[Chunk, int]] = []  # retries, and chunks a broken pool refused: before new ones
        self.breaks = 0  # in a row, without a chunk finished
        self.warned = False

    def run(self) -> None:
        try:
            self.fill()
            while self.pending:
                finished, _ = wait(list(self.pending), timeout=POLL, return_when=FIRST_COMPLETED)
                if not finished and self.alive is not None and not self.alive():
                    raise ExecutorError("the executor stopped answering (its Dask client has closed: the "
                                        "scheduler is gone)")
                for future in finished:
                    if future in self.pending:  # else dropped with its broken pool
                        self.collect(future, *self.pending.pop(future))
                while self.order and self.order[0] in self.ready:
                    self.done(self.ready.pop(self.order.pop(0)))
                self.fill()
        except BaseException:  # an interrupt, a lost executor: no worker left running; the rows given are kept
            for future in self.pending:
                future.cancel()
            if self.renew is not None:
                _stop(self.pool)
            raise
        if self.renew is not None:  # stopped, not shut down: a worker killed while it waited for work holds the
            _stop(self.pool)        # queue's lock, and the pool, not yet aware, would wait for the others for ever

    def submit(self, chunk: Chunk, attempt: int, alone: bool = False) -> None:
        """Hand a chunk to the executor; one it refuses waits for the renewed pool (or ends the sweep)."""
        try:
            future = self.pool.submit(worker.run_chunk, chunk)
        except (BrokenExecutor, RuntimeError) as exc:  # broken, or shut down
            if self.renew is None or not isinstance(exc, BrokenExecutor):
                raise ExecutorError(f"the executor refuses the sweep's chunks ({type(exc).__name__}: "
                                    f"{exc})") from None
            self.broke(exc)
            (self.suspects if alone else self.queue).insert(0, (chunk, attempt))  # it never ran: uncharged
            return
        self.pending[future] = (chunk, attempt, alone)

    def fill(self) -> None:
        """Submit what may run now: a suspect alone, else the queue, else new chunks up to ``in_flight``."""
        while True:
            if self.suspects:  # one at a time, so that a break is the running chunk's
                if self.pending:
                    return
                self.submit(*self.suspects.pop(0), alone=True)
            elif self.queue:
                self.submit(*self.queue.pop(0))
            elif len(self.pending) + len(self.ready) < self.in_flight:
                chunk = next(self.chunks, None)
                if chunk is None:
                    return
                self.order.append(chunk.start)
                self.submit(chunk, 1)
            else:
                return

    def collect(self, future: Future[ChunkResult], chunk: Chunk, attempt: int, alone: bool) -> None:
        """A finished future: its result kept, or its chunk retried, suspected or recorded "failed"."""
        if future.cancelled():  # not by the sweep: the executor dropped it
            if self.renew is None:
                raise ExecutorError("the executor cancelled the sweep's chunks (a Dask scheduler that is gone "
                                    "cancels every task)")
            error: BaseException = BrokenExecutor("the pool cancelled a chunk")
        else:
            try:
                self.ready[chunk.start] = future.result()
                self.breaks = 0
                return
            except Exception as exc:  # a chunk's failure is recorded, never the sweep's
                error = exc
        if isinstance(error, BrokenExecutor) and self.renew is not None:
            self.broke(error)
            if not alone:  # not known to be this chunk's doing: no attempt charged
                self.suspects.append((chunk, attempt))
                self.suspects.sort(key=lambda s: s[0].start)
                return
        if attempt >= ATTEMPTS:
            self.ready[chunk.start] = failed_result(chunk, error)
            self.breaks = 0
        elif alone:
            self.suspects.insert(0, (chunk, attempt + 1))
        else:
            self.queue.append((chunk, attempt + 1))

    def broke(self, error: BaseException) -> None:
        """The pool broke: a fresh pool, and each chunk that was in flight a suspect (finished ones kept)."""
        assert self.renew is not None
        self.breaks += 1
        if self.breaks > MAX_BREAKS:
            raise ExecutorError(f"the sweep's worker processes died {MAX_BREAKS} times in a row without "
                                f"finishing a chunk ({type(error).__name__}: {error})")
        if not self.warned:
            warnings.warn(BROKEN_POOL_WARNING, stacklevel=2)
            self.warned = True
        for future, (other, tries, _) in self.pending.items():
            if future.done() and not future.cancelled() and future.exception() is None:
                self.ready[other.start] = future.result()  # it finished before the break
            else:
                self.suspects.append((other, tries))
        self.pending.clear()
        self.suspects.sort(key=lambda s: s[0].start)
        _stop(self.pool)
        self.pool = self.renew()


def _stop(pool: Executor) -> None:
    """Stop a pool the sweep made, at once (:meth:`~isolator.sweep.pool.SweepPool.stop`; another executor
    is shut down, its queued chunks dropped)."""
    stop = getattr(pool, "stop", None)
    if callable(stop):
        stop()
    else:
        pool.shutdown(wait=False, cancel_futures=True)


def _serial(chunk: Chunk) -> ChunkResult:
    """A chunk in this process, retried once."""
    error: BaseException | None = None
    for _ in range(ATTEMPTS):
        try:
            return worker.run_chunk(chunk)
        except Exception as exc:  # a chunk's failure is recorded, never the sweep's
            error = exc
    assert error is not None
    return failed_result(chunk, error)
