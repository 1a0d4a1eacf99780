"""Chunks out to an executor, results back in design order: a bounded number in flight (memory flat),
a chunk that fails (its worker died, or it raised) retried once, then its rows recorded "failed".

When a worker of the sweep's own process pool dies, the pool is renewed; which of the chunks in flight
killed it is unknown, so each of them is run again alone (one at a time), without charging it an attempt.
A chunk that breaks the pool while it runs alone is the culprit: that counts as its attempt. Once the
suspects are cleared the chunks are handed out as before."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, Executor, Future, wait
from concurrent.futures.process import BrokenProcessPool

import numpy as np

from isolator.sweep import worker
from isolator.sweep.metrics import metric_columns
from isolator.sweep.worker import Chunk, ChunkResult

__all__ = ["ATTEMPTS", "failed_result", "run_chunks"]

#: tries of a chunk before its rows are recorded "failed"
ATTEMPTS = 2


def failed_result(chunk: Chunk, exc: BaseException) -> ChunkResult:
    """The rows of a chunk that failed every attempt: status "failed", the reason the last error."""
    n = chunk.params.shape[0]
    died = isinstance(exc, BrokenProcessPool)
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
        were in flight then run again alone, uncharged (see the module's description); None: a chunk
        whose executor broke is retried like one that raised.
    """
    if executor is None:
        for chunk in chunks:
            done(_serial(chunk))
        return
    pending: dict[Future[ChunkResult], tuple[Chunk, int, bool]] = {}  # chunk, attempt, run alone
    ready: dict[int, ChunkResult] = {}
    order: list[int] = []
    suspects: list[tuple[Chunk, int]] = []  # in flight when the pool broke: each to run alone
    pool = [executor]

    def submit(chunk: Chunk, attempt: int, alone: bool = False) -> None:
        pending[pool[0].submit(worker.run_chunk, chunk)] = (chunk, attempt, alone)

    def fill() -> None:
        if suspects:  # one at a time, so that a break is the running chunk's
            if not pending:
                submit(*suspects.pop(0), alone=True)
            return
        while len(pending) + len(ready) < in_flight:
            chunk = next(chunks, None)
            if chunk is None:
                return
            order.append(chunk.start)
            submit(chunk, 1)

    def broke(chunk: Chunk, attempt: int) -> None:
        """The pool broke while several chunks ran: a fresh pool, and each of them a suspect."""
        suspects.append((chunk, attempt))
        for future, (other, tries, _) in pending.items():
            if future.done() and not future.cancelled() and future.exception() is None:
                ready[other.start] = future.result()  # it finished before the break
            else:
                suspects.append((other, tries))
        pending.clear()
        suspects.sort(key=lambda s: s[0].start)

    try:
        fill()
        while pending:
            finished, _ = wait(list(pending), return_when=FIRST_COMPLETED)
            for future in finished:
                if future not in pending:  # dropped with its broken pool
                    continue
                chunk, attempt, alone = pending.pop(future)
                try:
                    ready[chunk.start] = future.result()
                    continue
                except Exception as exc:  # a chunk's failure is recorded, never the sweep's
                    error: BaseException = exc
                if isinstance(error, BrokenProcessPool) and renew is not None:
                    pool[0].shutdown(wait=False, cancel_futures=True)
                    pool[0] = renew()
                    if not alone:  # not known to be this chunk's doing: no attempt charged
                        broke(chunk, attempt)
                        continue
                if attempt >= ATTEMPTS:
                    ready[chunk.start] = failed_result(chunk, error)
                elif alone:
                    suspects.insert(0, (chunk, attempt + 1))
                else:
                    submit(chunk, attempt + 1)
            while order and order[0] in ready:
                done(ready.pop(order.pop(0)))
            fill()
    except BaseException:  # an interrupt: no worker left running; the rows given to ``done`` are kept
        for future in pending:
            future.cancel()
        if renew is not None:
            _stop(pool[0])
        raise
    if renew is not None:
        pool[0].shutdown()


def _stop(pool: Executor) -> None:
    """Stop a process pool the sweep made, at once: its workers terminated, its queued chunks dropped."""
    processes = getattr(pool, "_processes", None) or {}  # no public way to stop them before Python 3.14
    for process in list(processes.values()):
        process.terminate()
    pool.shutdown(wait=True, cancel_futures=True)  # the pool sees its workers gone and ends


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
