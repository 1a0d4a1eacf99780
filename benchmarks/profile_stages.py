"""Where the time of a batch and of a sweep goes, by stage (issue 36): the equilibria, the step plans, the
staged inputs, the compiled stepping, the metrics on the dense output, the free-motion judgement after the
run's end, and the rest (Python between them); for the sweep also the designs, the chunks' rows and the
output. Each stage's functions are wrapped with a timer (wall and CPU time of this thread); the batch and
the sweep run on one thread in this process.

    python benchmarks/profile_stages.py             # --runs 1000 --designs 20000
"""

from __future__ import annotations

import argparse
import functools
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path

import numpy as np

import isolator.simulation.batch as batchmod
import isolator.sweep.worker as workermod
from isolator import Simulator, load_scenario
from isolator.numerics.dop853 import DenseStepper
from isolator.sweep import sweep

TOTALS: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0])
OUTER: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0])
_ACTIVE: list[str] = []


def _timed(stage: str, fn: Callable, outer: bool = False) -> Callable:
    """``fn`` adding its wall and CPU time to ``stage`` (not again inside an enclosing stage; an ``outer``
    stage encloses the others without hiding them, and is left out of the rest)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        if outer:
            t0, c0 = time.perf_counter(), time.thread_time()
            try:
                return fn(*args, **kwargs)
            finally:
                OUTER[stage][0] += time.perf_counter() - t0
                OUTER[stage][1] += time.thread_time() - c0
        if _ACTIVE:
            return fn(*args, **kwargs)
        _ACTIVE.append(stage)
        t0, c0 = time.perf_counter(), time.thread_time()
        try:
            return fn(*args, **kwargs)
        finally:
            TOTALS[stage][0] += time.perf_counter() - t0
            TOTALS[stage][1] += time.thread_time() - c0
            _ACTIVE.pop()

    return wrapper


def _instrument() -> None:
    for name, stage in (("_equilibria", "equilibria (static rests, both ends)"),
                        ("solve_rests", "equilibria (static rests, both ends)"),
                        ("dense_metrics", "metrics on the dense output"),
                        ("run_tails", "free-motion judgement: Jacobians, modes, bound"),
                        ("judged_times", "free-motion judgement: verdict and reasons")):
        if hasattr(batchmod, name):
            setattr(batchmod, name, _timed(stage, getattr(batchmod, name)))
    try:  # the batch's judgement by parts (since issue 36)
        from isolator.simulation.tail_check import RunTails
    except ImportError:
        pass
    else:
        RunTails.of = classmethod(_timed("free-motion judgement: Jacobians, modes, bound", RunTails.of.__func__))
        RunTails.inside = _timed("free-motion judgement: Jacobians, modes, bound", RunTails.inside)
        RunTails.get = _timed("free-motion judgement: verdict and reasons", RunTails.get)
    DenseStepper.run_slots = _timed("stepping (compiled loop)", DenseStepper.run_slots)
    DenseStepper.states_at = staticmethod(_timed("free-motion judgement: end state", DenseStepper.states_at))
    Simulator.plan_inputs = _timed("staging (stage inputs)", Simulator.plan_inputs)
    Simulator.method_for = _timed("step plans", Simulator.method_for)


def _report(title: str, wall: float, cpu: float, runs: int) -> None:
    print(f"\n{title}: {wall:.3f} s wall, {cpu:.3f} s CPU, {runs} runs ({1e3 * cpu / runs:.3f} ms CPU per run)")
    print("| stage | wall [s] | CPU [s] | CPU per run [ms] | share of CPU |\n|---|---|---|---|---|")
    rest_w, rest_c = wall, cpu
    for stage, (w, c) in sorted(TOTALS.items(), key=lambda kv: -kv[1][1]):
        rest_w, rest_c = rest_w - w, rest_c - c
        print(f"| {stage} | {w:.3f} | {c:.3f} | {1e3 * c / runs:.3f} | {100 * c / cpu:.0f} % |")
    for stage, (w, c) in OUTER.items():  # e.g. the batches: the rest is then split inside and outside them
        inner_w, inner_c = w - (wall - rest_w), c - (cpu - rest_c)
        rest_w, rest_c = rest_w - inner_w, rest_c - inner_c
        print(f"| Python in {stage}, between the stages above | {inner_w:.3f} | {inner_c:.3f} | "
              f"{1e3 * inner_c / runs:.3f} | {100 * inner_c / cpu:.0f} % |")
    print(f"| the rest (Python between the stages) | {rest_w:.3f} | {rest_c:.3f} | {1e3 * rest_c / runs:.3f} | "
          f"{100 * rest_c / cpu:.0f} % |")
    TOTALS.clear()
    OUTER.clear()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--designs", type=int, default=20000)
    args = parser.parse_args()
    sim = Simulator(load_scenario("paper-table-3-2"))
    rng = np.random.default_rng(1)
    k, c = rng.uniform(0.5, 2.0, args.runs), rng.uniform(0.5, 4.0, args.runs)
    sim.run_batch(k, c, workers=1)  # compiles and plans
    _instrument()
    TOTALS.clear()
    t0, c0 = time.perf_counter(), time.thread_time()
    sim.run_batch(k, c, workers=1)
    _report(f"run_batch, {args.runs} runs (stiffness x0.5-2, damping x0.5-4), one thread", time.perf_counter() - t0,
            time.thread_time() - c0, args.runs)
    workermod.run_batch = _timed("the chunks' batches", workermod.run_batch, outer=True)
    with tempfile.TemporaryDirectory() as tmp:
        t0, c0 = time.perf_counter(), time.thread_time()
        sweep("paper-table-3-2", scale={"isolators[*].stiffness": (0.5, 2.0), "isolators[*].damping": (0.5, 4.0)},
              samples=args.designs, workers=1, out=Path(tmp) / "rows.csv")
        _report(f"sweep of {args.designs} designs in one process (workers=1), rows to CSV", time.perf_counter() - t0,
                time.thread_time() - c0, args.designs)


if __name__ == "__main__":
    main()
