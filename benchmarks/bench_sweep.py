"""Speed of sweeps on the paper's Table 3.2 case (12 s, 1 kHz), side by side with ``Simulator.run_batch``.

Prints each figure and its ratio to the baseline measured in the same run, today's batch
(``Simulator.run_batch``: stiffness and damping scales, two threads): sweeps of the same designs through
``isolator.sweep.sweep`` on the default local process pool, in one process, and (with ``distributed``
installed) on a Dask ``LocalCluster`` of two worker processes; one transient; and a long sweep streamed to
CSV with its peak memory. Run:  python benchmarks/bench_sweep.py [--runs 20000] [--long 100000]
"""

from __future__ import annotations

import argparse
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import timed

from isolator import Simulator, load_scenario
from isolator.sweep import chunk_size_for, default_workers, sweep
from isolator.sweep.worker import Chunk, run_chunk, scenario_key

SCENARIO = "paper-table-3-2"


def _designs(n: int, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.uniform(0.5, 2.0, n), rng.uniform(0.5, 4.0, n)


def _scales(k: np.ndarray, c: np.ndarray) -> dict[str, np.ndarray]:
    return {"isolators[*].stiffness": k, "isolators[*].damping": c}


def _peak_rss_mb() -> float:
    """Peak resident memory of this process and its finished children [MB]."""
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return max(own, children) / 1024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=20000, help="designs in the rate figures (and the Dask one)")
    parser.add_argument("--long", type=int, default=0, help="designs of the streamed sweep with its memory "
                        "(e.g. 100000; 0: skip)")
    parser.add_argument("--no-dask", action="store_true", help="skip the Dask LocalCluster figure")
    parser.add_argument("--repeat", type=int, default=3, help="repeats of each rate (the median is shown; the "
                        "machine's other load makes single figures vary by 30 %%)")
    args = parser.parse_args()
    n, workers = args.runs, default_workers()
    k, c = _designs(n)
    sim = Simulator(load_scenario(SCENARIO))
    sim.run_batch(k, c)  # warm-up: every plan and stepper the designs need
    t_base, _ = timed(lambda: sim.run_batch(k, c, workers=2), args.repeat)
    base = n / t_base
    print(f"baseline Simulator.run_batch, {n} runs, stiffness x0.5-2, damping x0.5-4, 2 threads: {base:7.0f} runs/s "
          f"(median of {args.repeat})")

    t_run, _ = timed(sim.run, 30)
    print(f"one transient, Simulator.run (equilibria, stepping, metrics): median {t_run * 1e3:6.2f} ms")

    def rate(repeat: int = args.repeat, **options: object) -> float:
        """Median runs per second of ``repeat`` sweeps of the designs, end to end."""
        dt, result = timed(lambda: sweep(SCENARIO, scale=_scales(k, c), zip=True, **options), repeat)  # type: ignore[arg-type]
        assert result.tally.failed == 0  # type: ignore[attr-defined]
        return n / dt

    sweep(SCENARIO, scale=_scales(k[:64], c[:64]), zip=True, workers=1)  # this process's simulator built
    pool = rate(workers=workers)
    print(f"sweep, default process pool ({workers} workers, chunks of {chunk_size_for(n, workers)}), end to end: "
          f"{pool:7.0f} runs/s (median of {args.repeat})   ratio {pool / base:5.2f}x the baseline; "
          f"per transient and core {workers / pool * 1e3:5.2f} ms")
    one = rate(1, workers=1)
    print(f"sweep in this process (workers=1): {one:7.0f} runs/s   ratio {one / base:5.2f}x the baseline")

    if not args.no_dask:
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            print("Dask figure skipped: distributed is not installed (pip install 'isolator[dask]')")
        else:
            with LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None) as cluster, \
                    Client(cluster) as client:
                t0 = time.perf_counter()
                sweep(SCENARIO, scale=_scales(k[:64], c[:64]), zip=True, executor=client.get_executor(), workers=2)
                warm = time.perf_counter() - t0
                tiny = Chunk(scenario_key(sim.scenario, "exact"), sim.scenario, "exact", 0, sim.parameters[None, :])
                t_here, _ = timed(lambda: run_chunk(tiny), 20)
                t_there, _ = timed(lambda: client.submit(run_chunk, tiny, pure=False).result(), 20)
                size = chunk_size_for(n, 2)
                print(f"Dask per-task overhead (one design, round trip less its run here): "
                      f"{(t_there - t_here) * 1e3:5.1f} ms; a chunk of {size} designs is about "
                      f"{size / one * 1e3:4.0f} ms of work on one core "
                      f"({(t_there - t_here) / (size / one):.1%} overhead)")
                dask = rate(executor=client.get_executor(), workers=2)
            print(f"sweep on a Dask LocalCluster (2 worker processes, 1 thread each; first 64-design sweep "
                  f"{warm:.2f} s): {dask:7.0f} runs/s (median of {args.repeat})   "
                  f"ratio {dask / pool:5.2f}x the local pool")

    if args.long:
        k_long, c_long = _designs(args.long, seed=2)
        with tempfile.TemporaryDirectory() as folder:
            for m in sorted({min(args.long, 10000), args.long}):
                t0 = time.perf_counter()
                result = sweep(SCENARIO, scale=_scales(k_long[:m], c_long[:m]), zip=True, workers=workers,
                               out=Path(folder) / f"sweep{m}.csv")
                dt = time.perf_counter() - t0
                print(f"streamed sweep, {m} runs to CSV: {dt:7.1f} s ({m / dt:6.0f} runs/s), "
                      f"{result.tally.failed} not ok, peak RSS so far {_peak_rss_mb():6.0f} MB")


if __name__ == "__main__":
    main()
