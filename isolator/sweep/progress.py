"""How far a sweep has got, on stderr, once it has run :data:`DELAY` s (a shorter sweep shows nothing): a
bar on a terminal, else (a log file, a pipe, a batch job) one line per tenth of the designs."""

from __future__ import annotations

import io
import os
import sys
import time
from collections.abc import Callable
from typing import Any, TextIO

__all__ = ["DELAY", "Progress", "progress_bar", "worker_notice"]

#: how long [s] a sweep runs before its progress shows
DELAY = 2.0


class Progress:
    """``progress(k)`` counts k more designs done, ``progress(-1)`` ends the display.

    Parameters
    ----------
    total : int
        Designs in the sweep.
    initial : int
        Done before (resumed from the file).
    stream : text file
        Where to show it (stderr).
    terminal : bool
        A bar (tqdm) rather than lines.
    delay : float
        [s] before anything shows.
    """

    def __init__(self, total: int, initial: int, stream: TextIO, terminal: bool, delay: float = DELAY) -> None:
        self.total, self.done, self.stream, self.terminal, self.delay = total, initial, stream, terminal, delay
        self.started = time.monotonic()
        self.tenth = self._tenth()  # the last tenth reached (a line is written for each one after the delay)
        self.bar: Any = None

    def _tenth(self) -> int:
        return (10 * self.done) // self.total if self.total else 10

    def __call__(self, k: int) -> None:
        if k < 0:
            if self.bar is not None:
                self.bar.close()
            return
        self.done += k
        elapsed = time.monotonic() - self.started
        if self.terminal:
            if self.bar is not None:
                self.bar.update(k)
            elif elapsed >= self.delay:
                from tqdm import tqdm

                tqdm.monitor_interval = 0  # no monitor thread: the pool's workers are forked while it runs
                columns, lines = _size(self.stream)
                self.bar = tqdm(total=self.total, initial=self.done, unit="run", file=self.stream, smoothing=0.1,
                                ncols=columns, nrows=lines)
            return
        tenth = self._tenth()
        if tenth > self.tenth:
            self.tenth = tenth
            if elapsed >= self.delay:
                print(f"isolator sweep: {10 * tenth} % ({self.done} of {self.total} designs, {elapsed:.1f} s)",
                      file=self.stream, flush=True)


def _size(stream: TextIO) -> tuple[int, int]:
    """The terminal's columns and lines (80 x 24 where it does not say: one that reports 0 would hide the bar)."""
    try:
        size = os.get_terminal_size(stream.fileno())
    except (OSError, ValueError, AttributeError, io.UnsupportedOperation):
        return 80, 24
    return size.columns or 80, size.lines or 24


def progress_bar(progress: bool, total: int, initial: int) -> Callable[[int], None]:
    """The sweep's progress on stderr when asked (:class:`Progress`), else nothing."""
    if not progress:
        return lambda k: None
    return Progress(total, initial, sys.stderr, sys.stderr.isatty())


def worker_notice(progress: bool, stream: TextIO | None = None, delay: float = DELAY) -> Callable[[Any], None]:
    """Called with a Dask client while no chunk finishes: once the sweep has run ``delay`` s, one line when
    the cluster has no workers (the sweep would otherwise wait in silence), and one when workers come."""
    if not progress:
        return lambda client: None
    started, said = time.monotonic(), [False]

    def notice(client: Any) -> None:
        if time.monotonic() - started < delay:
            return
        try:
            workers = len(client.scheduler_info().get("workers", {}))
        except Exception:  # a client closing: the runner finds out
            return
        if (workers == 0) != said[0]:
            said[0] = workers == 0
            text = ("0 workers: the chunks wait until a worker joins the scheduler (dask worker "
                    f"{client.scheduler.address})" if workers == 0 else f"{workers} workers joined")
            print(f"isolator sweep: {text}", file=stream or sys.stderr, flush=True)

    return notice
