"""How far a sweep has got: a bar on a terminal, else a line per tenth of the designs."""

from __future__ import annotations

import sys
from collections.abc import Callable

__all__ = ["progress_bar"]


def progress_bar(progress: bool, total: int, initial: int) -> Callable[[int], None]:
    """A tqdm bar on stderr, when asked and stderr is a terminal: ``bar(k)`` adds k runs, ``bar(-1)`` closes."""
    if not (progress and sys.stderr.isatty()):
        return lambda k: None
    from tqdm import tqdm

    tqdm.monitor_interval = 0  # no monitor thread: the pool's workers are forked after the bar starts
    shown = tqdm(total=total, initial=initial, unit="run", file=sys.stderr, smoothing=0.1)
    return lambda k: shown.close() if k < 0 else shown.update(k)
