"""Where the time of one 12 s transient goes, by stage (issue 43, item 1): ``Simulator.run`` on the bundled
paper scenario, warm (compiled, planned), each stage's functions wrapped with a timer as
``profile_stages.py`` wraps a batch's: the parameter vector and the tipping check, the two static rests,
the step plan, the staged inputs, the compiled loop, the end state, the free-motion judgement after the
run's end, the metrics, the points and windows, the response, and the rest (Python between them).

    python benchmarks/profile_transient.py             # --runs 2000 --scenario paper-table-3-2
"""

from __future__ import annotations

import argparse
import time

from profile_stages import TOTALS, _report, _timed

import isolator.simulation.simulator as simmod
from isolator import Simulator, load_scenario
from isolator.numerics.dop853 import DenseStepper
from isolator.simulation.response import Response


def _instrument() -> None:
    Simulator.parameter_vector = _timed("parameters and the tipping check", Simulator.parameter_vector)
    Simulator.check_tipping = _timed("parameters and the tipping check", Simulator.check_tipping)
    Simulator.equilibria = _timed("equilibria (static rests, both ends)", Simulator.equilibria)
    Simulator.method_of = _timed("step plan (the method's choice)", Simulator.method_of)
    Simulator.plan_inputs = _timed("staging (stage inputs)", Simulator.plan_inputs)
    DenseStepper.run_slots = _timed("stepping (compiled loop, samples and probes)", DenseStepper.run_slots)
    DenseStepper.signal_values = _timed("final rest's signals", DenseStepper.signal_values)
    DenseStepper.states_at = staticmethod(_timed("end state (dense output)", DenseStepper.states_at))
    simmod.run_tail = _timed("free-motion judgement: Jacobians, modes", simmod.run_tail)
    simmod.run_metrics = _timed("metrics on the dense output and the free motion", simmod.run_metrics)
    simmod.run_points = _timed("points and windows", simmod.run_points)
    simmod.with_random_margins = _timed("points and windows", simmod.with_random_margins)
    simmod.sensor_history = _timed("the response (sensors, columns)", simmod.sensor_history)
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
