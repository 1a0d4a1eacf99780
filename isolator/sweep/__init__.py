"""Sweeps over any named model parameter, on any executor: :func:`sweep` and its :class:`SweepResult`.

The designs (:mod:`~isolator.sweep.designs`, names in :mod:`~isolator.sweep.names`) go out in chunks
(:mod:`~isolator.sweep.runner`) to workers that build the scenario's simulator once
(:mod:`~isolator.sweep.worker`); the rows come back in design order and are streamed to CSV or Parquet
(:mod:`~isolator.sweep.output`).
"""

from __future__ import annotations

from isolator.sweep.designs import METHODS, Designs, build_designs
from isolator.sweep.names import Column, resolve
from isolator.sweep.result import SweepResult, Tally
from isolator.sweep.sweep import chunk_size_for, default_workers, sweep

__all__ = [
    "METHODS",
    "Column",
    "Designs",
    "SweepResult",
    "Tally",
    "build_designs",
    "chunk_size_for",
    "default_workers",
    "resolve",
    "sweep",
]
