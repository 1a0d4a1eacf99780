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
process ids the workers reported from the initializer, terminated through :func:`multiprocessing.active_children`
(never another process that happens to reuse an id).
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
from typing import Any

__all__ = ["WATCH_INTERVAL", "SweepPool"]

#: how often [s] a worker checks that its sweep is alive (the portable path)
WATCH_INTERVAL = 0.5
#: prctl option: the signal a process receives when its parent dies (linux/prctl.h)
_PR_SET_PDEATHSIG = 1


def _context() -> Any:
    """Fork where the platform can (the workers inherit the simulator already built), else its default."""
    return multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else None)


class SweepPool(ProcessPoolExecutor):
    """A process pool whose workers end with the process that made it.

    Parameters
    ----------
    workers : int
        Worker processes.
    """

    def __init__(self, workers: int) -> None:
        context = _context()
        self._reports = context.SimpleQueue()
        self._pids: set[int] = set()
        super().__init__(max_workers=workers, mp_context=context, initializer=_started,
                         initargs=(os.getpid(), self._reports))

    def worker_pids(self) -> set[int]:
        """The process ids of the workers started so far (those that have run the initializer)."""
        while not self._reports.empty():
            self._pids.add(int(self._reports.get()))
        return set(self._pids)

    def stop(self) -> None:
        """End the pool at once: its workers terminated (SIGTERM), its queued chunks dropped."""
        terminate = getattr(super(), "terminate_workers", None)  # Python 3.14
        if terminate is not None:
            terminate()
            return
        mine = self.worker_pids()
        for child in multiprocessing.active_children():
            if child.pid in mine:
                child.terminate()
        self.shutdown(wait=True, cancel_futures=True)  # the pool sees its workers gone and ends


def _started(parent: int, reports: Any) -> None:
    """The pool's initializer, in each worker: report the process id, then end with the sweep."""
    reports.put(os.getpid())
    watched = os.getppid()
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
