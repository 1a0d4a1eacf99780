"""Sweeps that lose worker processes (real SIGKILLs, at chosen moments found by hooks, never by sleeps):
the sweep's own pool is renewed and every row kept, equal to an undisturbed run; an executor the sweep
cannot renew ends it with one error naming --resume, the rows kept; the pool is stopped with public API."""

from __future__ import annotations

import importlib
import multiprocessing
import os
import signal
import sys
import threading
import time
import warnings
from collections.abc import Callable
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from concurrent.futures.thread import BrokenThreadPool
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import isolator.sweep.runner as runner
from isolator.cli.app import main
from isolator.errors import ExecutorError, ParameterError
from isolator.sweep import sweep
from isolator.sweep.pool import SweepPool

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="SIGKILL and fork")

SCENARIO = "paper-table-3-2"
DAMPING = {"isolators[*].damping": [0.5 + 0.02 * i for i in range(64)]}
SWEEP_MODULE = importlib.import_module("isolator.sweep.sweep")
DEADLINE = 60.0  # [s] for a process to end, generous on a loaded machine


@pytest.fixture(scope="module")
def undisturbed(tmp_path_factory) -> bytes:
    """The rows of the sweep run through without a fault (CSV bytes)."""
    out = tmp_path_factory.mktemp("undisturbed") / "rows.csv"
    sweep(SCENARIO, scale=DAMPING, workers=1, out=out)
    return out.read_bytes()


def on_each_chunk(monkeypatch: pytest.MonkeyPatch, action: Callable[[int, Executor | None], None]) -> None:
    """Call ``action(number of chunks done, first executor)`` after each chunk's rows are written."""
    original = runner.run_chunks

    def hooked(chunks: Any, executor: Executor | None, in_flight: int, done: Any, *rest: Any) -> None:
        count = [0]

        def after(result: Any) -> None:
            done(result)
            count[0] += 1
            action(count[0], executor)

        original(chunks, executor, in_flight, after, *rest)

    monkeypatch.setattr(SWEEP_MODULE, "run_chunks", hooked)


def gone(pid: int) -> bool:
    """Whether the process has ended (and been reaped, or is a zombie)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] in ("Z", "X")
    except (FileNotFoundError, ProcessLookupError):
        return True


def wait_until(condition: Callable[[], bool], what: str) -> None:
    end = time.monotonic() + DEADLINE
    while not condition():
        if time.monotonic() > end:
            pytest.fail(f"not within {DEADLINE:g} s: {what}")
        time.sleep(0.01)


def kill_a_worker(wait_for_the_pool: bool) -> list[int]:
    """SIGKILL one worker of the running pool; with ``wait_for_the_pool``, return once the pool has seen it
    (it terminates the other workers after marking itself broken): the next submission meets a broken pool."""
    workers = sorted(p.pid for p in multiprocessing.active_children() if p.pid is not None)
    assert workers, "no pool worker to kill"
    os.kill(workers[0], signal.SIGKILL)
    if wait_for_the_pool:
        wait_until(lambda: all(gone(pid) for pid in workers), "the pool ending its other workers")
    return workers


# when (after how many chunks), and whether to wait for the pool to notice before the sweep goes on
MOMENTS = {
    "right after the first chunk, the pool broken before the next submission": ((1,), True),
    "right after the first chunk, at once": ((1,), False),
    "mid-sweep": ((7,), False),
    "after the last chunk was handed out": ((14,), False),
    "twice": ((3, 9), True),
}


@pytest.mark.parametrize("moment", list(MOMENTS))
def test_a_worker_killed_at_any_moment_costs_no_row(moment, monkeypatch, tmp_path, undisturbed):
    after, wait_for_the_pool = MOMENTS[moment]
    killed: list[int] = []

    def action(chunks_done: int, _: Executor | None) -> None:
        if chunks_done in after:
            killed.extend(kill_a_worker(wait_for_the_pool))

    on_each_chunk(monkeypatch, action)
    out = tmp_path / "rows.csv"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = sweep(SCENARIO, scale=DAMPING, workers=2, chunk_size=4, out=out)
    assert killed
    breaks = [w for w in caught if "renewed its pool" in str(w.message)]
    # one warning however many breaks (none when the last chunks were done before the pool saw its loss)
    assert len(breaks) == (1 if after[-1] < 14 else len(breaks)) <= 1
    assert result.tally.runs == 64
    assert out.read_bytes() == undisturbed  # every row, bit for bit
    assert multiprocessing.active_children() == []


def test_a_worker_killed_before_any_chunk_lands_costs_no_row(monkeypatch, tmp_path, undisturbed):
    original = runner.run_chunks
    killed = threading.Event()

    def killer(pool: SweepPool) -> None:
        wait_until(lambda: len(pool.worker_pids()) == 2, "the workers starting")
        os.kill(min(pool.worker_pids()), signal.SIGKILL)
        killed.set()

    def hooked(chunks: Any, executor: Any, *rest: Any) -> None:
        threading.Thread(target=killer, args=(executor,), daemon=True).start()
        original(chunks, executor, *rest)

    monkeypatch.setattr(SWEEP_MODULE, "run_chunks", hooked)
    out = tmp_path / "rows.csv"
    with pytest.warns(UserWarning, match="renewed its pool"):
        sweep(SCENARIO, scale=DAMPING, workers=2, chunk_size=4, out=out)
    assert killed.is_set()
    assert out.read_bytes() == undisturbed


def test_the_command_survives_a_killed_worker_with_one_warning(monkeypatch, tmp_path, capsys, undisturbed):
    on_each_chunk(monkeypatch, lambda n, _: kill_a_worker(True) if n == 2 else None)
    out = tmp_path / "rows.csv"
    status = main(["sweep", SCENARIO, "--scale", "isolators[*].damping=" + ",".join(
        repr(v) for v in DAMPING["isolators[*].damping"]), "--workers", "2", "--chunk-size", "4", "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 0
    assert err.count("isolator: warning:") == 1
    assert "renewed its pool" in err
    assert "Traceback" not in err
    assert out.read_bytes() == undisturbed


def test_a_pool_the_sweep_cannot_renew_ends_it_with_resume_named(monkeypatch, tmp_path, undisturbed):
    out = tmp_path / "rows.csv"
    context = multiprocessing.get_context("fork")
    with ProcessPoolExecutor(2, mp_context=context) as pool:  # the caller's: the sweep cannot make another
        on_each_chunk(monkeypatch, lambda n, _: kill_a_worker(True) if n == 2 else None)
        with pytest.raises(ExecutorError, match=r"rows done are kept in .*resume=True to finish"):
            sweep(SCENARIO, scale=DAMPING, executor=pool, workers=2, chunk_size=4, out=out)
    monkeypatch.undo()
    kept = out.read_bytes()
    assert kept.count(b"\n") >= 1 + 8
    assert undisturbed.startswith(kept)
    sweep(SCENARIO, scale=DAMPING, workers=2, out=out, resume=True)
    assert out.read_bytes() == undisturbed


def test_an_executor_shut_down_under_the_sweep_is_one_error():
    pool = ThreadPoolExecutor(2)
    pool.shutdown()
    with pytest.raises(ExecutorError, match=r"refuses the sweep's chunks .*resume=True"):
        sweep(SCENARIO, scale=DAMPING, executor=pool, workers=2, chunk_size=4)


def test_a_pool_that_breaks_as_it_starts_is_one_error(monkeypatch):
    class Doomed(SweepPool):
        """A pool found broken at every submission (as one whose workers die as they start)."""

        def submit(self, fn: Any, /, *args: Any, **kwargs: Any) -> Any:
            raise BrokenProcessPool("a child process terminated abruptly")

    monkeypatch.setattr(SWEEP_MODULE, "SweepPool", Doomed)
    with pytest.warns(UserWarning, match="renewed its pool"), \
            pytest.raises(ExecutorError, match="died 5 times in a row"):
        sweep(SCENARIO, scale=DAMPING, workers=2, chunk_size=4)
    assert multiprocessing.active_children() == []


def test_stopping_the_pool_ends_its_workers_at_once():
    pool = SweepPool(2)
    future = pool.submit(time.sleep, 60.0)  # a chunk that would run for a minute
    wait_until(lambda: len(pool.worker_pids()) == 2, "the workers starting")
    pids = pool.worker_pids()
    started = time.monotonic()
    pool.stop()
    assert time.monotonic() - started < 30.0
    assert all(gone(pid) for pid in pids)
    assert future.done()


def test_workers_end_when_their_pool_s_process_is_killed(tmp_path):
    """A process that made a SweepPool is SIGKILLed: its workers end (they watch it)."""
    import subprocess

    code = ("import sys, time\nfrom isolator.sweep.pool import SweepPool\npool = SweepPool(2)\n"
            "pool.submit(time.sleep, 600)\npool.submit(time.sleep, 600)\n"
            "while len(pool.worker_pids()) < 2: time.sleep(0.01)\n"
            "print(*sorted(pool.worker_pids()), flush=True)\ntime.sleep(600)\n")
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, env=env)
    try:
        assert proc.stdout is not None
        pids = [int(w) for w in proc.stdout.readline().split()]
        assert len(pids) == 2
        assert not any(gone(pid) for pid in pids)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(DEADLINE)
        wait_until(lambda: all(gone(pid) for pid in pids), "the orphaned workers ending")
    finally:
        proc.kill()
        proc.wait()
    assert np.all([gone(pid) for pid in pids])


def test_a_caller_s_executor_made_by_a_function_is_renewed_when_it_breaks(tmp_path, undisturbed):
    made: list[Executor] = []

    class Breaking(ThreadPoolExecutor):
        """The first one made refuses work after three chunks, as a broken pool does."""

        def submit(self, fn: Any, /, *args: Any, **kwargs: Any) -> Any:
            self.handed = getattr(self, "handed", 0) + 1
            if self is made[0] and self.handed > 3:
                raise BrokenThreadPool("a worker thread's initializer failed")
            return super().submit(fn, *args, **kwargs)

    def make() -> Executor:
        made.append(Breaking(2))
        return made[-1]

    out = tmp_path / "rows.csv"
    with pytest.warns(UserWarning, match="renewed its pool"):
        sweep(SCENARIO, scale=DAMPING, executor=make, workers=2, chunk_size=4, out=out)
    assert len(made) == 2
    assert out.read_bytes() == undisturbed
    with pytest.raises(ParameterError, match=r"^executor: must be a concurrent\.futures\.Executor or a function"):
        sweep(SCENARIO, scale=DAMPING, executor=42, out=tmp_path / "none.csv")  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"^executor: the function must return"):
        sweep(SCENARIO, scale=DAMPING, executor=lambda: 42, out=tmp_path / "none.csv")  # type: ignore[arg-type]
    assert not (tmp_path / "none.csv").exists()
