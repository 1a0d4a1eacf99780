"""Chunks out to an executor, results back in design order: a bounded number in flight (memory flat),
a chunk that fails (its worker died, or it raised) retried once, then its rows recorded "failed"."""

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
        A fresh executor when the current one broke (a process pool whose worker died); None: the
        chunks then fail.
    """
    if executor is None:
        for chunk in chunks:
            done(_serial(chunk))
        return
    pending: dict[Future[ChunkResult], tuple[Chunk, int, int]] = {}
    ready: dict[int, ChunkResult] = {}
    order: list[int] = []
    generation = [0]
    pool = [executor]

    def submit(chunk: Chunk, attempt: int) -> None:
        pending[pool[0].submit(worker.run_chunk, chunk)] = (chunk, attempt, generation[0])

    def fill() -> None:
        while len(pending) + len(ready) < in_flight:
            chunk = next(chunks, None)
            if chunk is None:
                return
            order.append(chunk.start)
            submit(chunk, 1)

    try:
        fill()
        while pending:
            finished, _ = wait(list(pending), return_when=FIRST_COMPLETED)
            for future in finished:
                chunk, attempt, born = pending.pop(future)
                try:
                    ready[chunk.start] = future.result()
                    continue
                except Exception as exc:  # a chunk's failure is recorded, never the sweep's
                    error: BaseException = exc
                if isinstance(error, BrokenProcessPool) and renew is not None and born == generation[0]:
                    pool[0].shutdown(wait=False, cancel_futures=True)
                    pool[0] = renew()
                    generation[0] += 1
                if attempt < ATTEMPTS:
                    submit(chunk, attempt + 1)
                else:
                    ready[chunk.start] = failed_result(chunk, error)
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
