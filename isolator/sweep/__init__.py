"""Sweeps over any named model parameter, on any executor: :func:`sweep` and its :class:`SweepResult`.

The designs (:mod:`~isolator.sweep.designs`, names in :mod:`~isolator.sweep.names`) go out in chunks
(:mod:`~isolator.sweep.runner`) to workers that build the scenario's simulator once
(:mod:`~isolator.sweep.worker`); the rows come back in design order and are streamed to CSV or Parquet
(:mod:`~isolator.sweep.output`).

Executors: the default is a local process pool (``workers`` processes, forked where the platform can, so that
they inherit the simulator built here; ``workers=1`` runs in this process), renewed when a worker dies, its
workers ending with the sweep (:mod:`~isolator.sweep.pool`). Any :class:`concurrent.futures.Executor` works, as
the tasks are plain picklable functions and dataclasses: a Dask cluster (``pip install "isolator[dask]"``;
``sweep(..., scheduler="tls://HOST:PORT", security=tls_security(ca, cert, key))``, ``isolator sweep --scheduler
tls://HOST:PORT --tls-ca-file CA --tls-cert CERT --tls-key KEY``: :mod:`~isolator.sweep.cluster`), or mpi4py's
``MPIPoolExecutor`` (``mpiexec -n 9 python -m mpi4py.futures script.py`` with ``sweep(...,
executor=MPIPoolExecutor, workers=8)``: the class, so that a broken one is made again). Each worker builds the
scenario's simulator on its first chunk (the compiled model comes from its own cache, ``ISOLATOR_CACHE``) and
reuses it. An executor lost mid-sweep is an :class:`~isolator.errors.ExecutorError`; ``resume=True`` finishes.
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
