"""Speed of active control on the paper's active Table 3.2 case.

Prints each figure and its ratio to a baseline measured in the same run:

* optimal feedforward against the allocation it improves on;
* the time-varying simulation with a sampled feedback controller (the
  compiled closed loop, :mod:`isolator.simulation.sampled_loop`) against the
  same simulation with the allocation's forces precomputed (compiled chunks).

Run:  python benchmarks/bench_control.py
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import timed

from controllers import feedback as fb
from controllers.feedforward import feedforward_allocation, feedforward_optimal
from isolator import Simulator, load_scenario
from isolator.analysis.linear import linearise


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    scenario = load_scenario("paper-table-3-2-active")
    sim = Simulator(scenario)
    lin = linearise(scenario)
    law = fb.feedback_law(scenario, fb.skyhook(lin, 5e4))
    allocation = feedforward_allocation(scenario)
    sim.run(feedback=law)  # compile the one-interval step
    t_alloc, _ = timed(lambda: feedforward_allocation(scenario), args.repeat)
    t_opt, ff = timed(lambda: feedforward_optimal(scenario), args.repeat)
    t_open, _ = timed(lambda: sim.run(forces=allocation.forces), args.repeat)
    t_loop, _ = timed(lambda: sim.run(feedback=law), args.repeat)
    info = ff.info  # type: ignore[attr-defined]
    print(f"feedforward by allocation (median):                       {t_alloc * 1e3:9.1f} ms")
    print(f"optimal feedforward, {info['knots']} knots, {info['variables']} variables (median): "
          f"{t_opt * 1e3:9.1f} ms   ratio {t_opt / t_alloc:5.1f}x the allocation")
    print(f"12 s simulation with precomputed forces (median):         {t_open * 1e3:9.1f} ms")
    print(f"12 s simulation with skyhook feedback at 1 kHz (median):   {t_loop * 1e3:9.1f} ms   "
          f"ratio {t_loop / t_open:5.1f}x the open-loop run")


if __name__ == "__main__":
    main()
