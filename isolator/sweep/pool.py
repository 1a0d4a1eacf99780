"""The sweep's own process pool: workers forked from the sweep (they inherit the simulator built there) that
end with it, and are stopped at once when it is interrupted.

Workers end with their sweep, however it ends (SIGKILL, the OOM killer): each worker, in the pool's
initializer,

* on Linux asks the kernel for SIGKILL when its parent dies (``prctl(PR_SET_PDEATHSIG)``): at once, even
  while the worker is deep in compiled code holding the GIL;
* everywhere, watches its parent from a daemon thread (every :data:`WATCH_INTERVAL` s) and exits when it
  has been re-parented (its parent gone): the portable path, and a second one on Linux.

A process group would not do: the sweep would have to lead it (a shell's job control already does), and a
group is ended by whoever signals it, not when the sweep dies.

Stopping a pool (:meth:`SweepPool.stop`) uses public API only: Python 3.14's ``terminate_workers``, else the
pool's own worker processes, which it creates through the multiprocessing context it is given (a context that
keeps the :class:`multiprocessing.Process` objects it makes): each terminated through its object, never through
a process id another process may have taken since.
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing
import os
import signal
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from typing import TYPE_CHECKING, Any, cast

if TYPE_CHECKING:
    from multiprocessing.context import BaseContext

__all__ = ["WATCH_INTERVAL", "SweepPool"]

#: how often [s] a worker checks that its sweep is alive (the portable path)
WATCH_INTERVAL = 0.5
#: prctl option: the signal a process receives when its parent dies (linux/prctl.h)
_PR_SET_PDEATHSIG = 1


def _context() -> Any:
    """Fork where the platform can (the workers inherit the simulator already built), else its default."""
    return multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else None)


class _Recording:
    """A multiprocessing context that keeps every process it makes (the pool makes its workers with it)."""

    def __init__(self, base: Any) -> None:
        self._base = base
        self.made: list[Any] = []

    def __getattr__(self, name: str) -> Any:
        return getattr(self._base, name)

    def Process(self, *args: Any, **kwargs: Any) -> Any:  # noqa: N802 (the context's own name)
        process = self._base.Process(*args, **kwargs)
        self.made.append(process)
        return process


class SweepPool(ProcessPoolExecutor):
    """A process pool whose workers end with the process that made it.

    Parameters
    ----------
    workers : int
        Worker processes.
    """

    def __init__(self, workers: int) -> None:
        self._recording = _Recording(_context())
        super().__init__(max_workers=workers, mp_context=cast("BaseContext", self._recording),
                         initializer=_started, initargs=(os.getpid(),))

    def worker_pids(self) -> set[int]:
        """The process ids of the pool's workers running now."""
        return {p.pid for p in self._recording.made if p.pid is not None and p.exitcode is None}

    def stop(self) -> None:
        """End the pool at once: its workers terminated (SIGTERM), its queued chunks dropped."""
        terminate = getattr(super(), "terminate_workers", None)  # Python 3.14
        if terminate is not None:
            terminate()
            return
        for process in self._recording.made:
            if process.pid is not None and process.exitcode is None:  # started, not ended
                process.terminate()
        self.shutdown(wait=True, cancel_futures=True)  # the pool sees its workers gone and ends


def _started(parent: int) -> None:
    """The pool's initializer, in each worker: end with the sweep."""
    watched = os.getppid()
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # not the command's handler (forked): stop() ends it at once
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    if watched == 1 or (watched != parent and _context().get_start_method() == "fork"):
        os._exit(1)  # the sweep died before the watch began
    threading.Thread(target=_watch, args=(watched,), name="isolator-sweep-watch", daemon=True).start()


def _watch(parent: int) -> None:
    """Exit this worker once it has been re-parented: the process that started it has died."""
    while os.getppid() == parent:
        time.sleep(WATCH_INTERVAL)
    os._exit(1)
