"""Where the time of one 12 s transient goes, by stage (issue 43, item 1): ``Simulator.run`` on the bundled
paper scenario, warm (compiled, planned), each stage's functions wrapped with a timer as
``profile_stages.py`` wraps a batch's: the parameter vector and the tipping check, the two static rests,
the step plan, the staged inputs, the compiled loop, the end state, the free-motion judgement after the
run's end, the metrics, the points and windows, the response, and the rest (Python between them). An older
tree's (one without some of these names) with ``PYTHONPATH=<tree>``.

    python benchmarks/profile_transient.py             # --runs 2000 --scenario paper-table-3-2
    PYTHONPATH=/tmp/old python benchmarks/profile_transient.py
"""

from __future__ import annotations

import argparse
import time

from profile_stages import TOTALS, _report, _timed

import isolator.simulation.simulator as simmod
from isolator import Simulator, load_scenario
from isolator.numerics.dop853 import DenseStepper
from isolator.simulation.response import Response


def _wrap(owner: object, name: str, stage: str, static: bool = False) -> None:
    """Time ``owner.name`` as ``stage`` (nothing when an older tree has no such name)."""
    if hasattr(owner, name):
        timed = _timed(stage, getattr(owner, name))
        setattr(owner, name, staticmethod(timed) if static else timed)


def _instrument() -> None:
    for name in ("parameter_vector", "check_tipping"):
        _wrap(Simulator, name, "parameters and the tipping check")
    _wrap(Simulator, "equilibria", "equilibria (static rests, both ends)")
    _wrap(Simulator, "method_of" if hasattr(Simulator, "method_of") else "method_for",
          "step plan (the method's choice)")
    _wrap(Simulator, "plan_inputs", "staging (stage inputs)")
    _wrap(DenseStepper, "run_slots", "stepping (compiled loop, samples and probes)")
    _wrap(DenseStepper, "signal_values", "final rest's signals")
    _wrap(DenseStepper, "states_at", "end state (dense output)", static=True)
    _wrap(simmod, "run_tail", "free-motion judgement: Jacobians, modes")
    _wrap(simmod, "run_metrics", "metrics on the dense output and the free motion")
    for name in ("run_points", "with_random_margins"):
        _wrap(simmod, name, "points and windows")
    _wrap(simmod, "sensor_history", "the response (sensors, columns)")
    simmod.Response = _timed("the response (sensors, columns)", Response)  # type: ignore[assignment]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=2000)
    parser.add_argument("--scenario", default="paper-table-3-2")
    args = parser.parse_args()
    sim = Simulator(load_scenario(args.scenario))
    for _ in range(20):  # compiles, plans, warms the caches
        sim.run()
    t0, c0 = time.perf_counter(), time.thread_time()
    for _ in range(args.runs):
        sim.run()
    bare_wall, bare_cpu = time.perf_counter() - t0, time.thread_time() - c0
    print(f"{args.scenario}: one transient {1e3 * bare_wall / args.runs:.3f} ms wall, "
          f"{1e3 * bare_cpu / args.runs:.3f} ms CPU (uninstrumented, mean of {args.runs})")
    _instrument()
    sim.run()
    TOTALS.clear()
    t0, c0 = time.perf_counter(), time.thread_time()
    for _ in range(args.runs):
        sim.run()
    _report(f"Simulator.run, {args.runs} runs, instrumented", time.perf_counter() - t0, time.thread_time() - c0,
            args.runs)


if __name__ == "__main__":
    main()
