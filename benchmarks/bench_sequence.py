"""Speed of a step-and-settle sequence: the bundled paper-table-3-2-sequence (Table 3.2's table and stages,
a 5 x 4 serpentine grid, +-50 nm probe window, measure 0.1 s: about 90 s of motion and settling).

Prints each figure and its ratio to a baseline measured in the same run: the same moves as a fixed-time
run (each carriage's steps chained into one profile at the start times the sequence found, simulated as an
ordinary scenario by ``Simulator.run``), so the ratio is what the event logic (running each step in chunks
until the window rule is decided, the equilibria per step, the stitching) costs. Both timings include
building the run (``Simulator(...)`` for the fixed-time run; the compiled model is cached for both).
Run:  python benchmarks/bench_sequence.py
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import timed

from isolator import Simulator, load_scenario, run_sequence
from isolator.simulation.sequence import chain_scenario


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=20, help="repeats of each timing (median)")
    parser.add_argument("--model", choices=("exact", "paper"), default="exact")
    args = parser.parse_args()
    sc = load_scenario("paper-table-3-2-sequence")
    result = run_sequence(sc, args.model)  # warm: the compiled model and steppers
    fixed = chain_scenario(sc, result)
    Simulator(fixed, args.model).run()
    steps = len(result.steps)
    total = result.total_time or float("nan")
    t_fixed, _ = timed(lambda: Simulator(fixed, args.model).run(), args.repeat)
    t_seq, result = timed(lambda: run_sequence(sc, args.model), args.repeat)
    print(f"scenario: {sc.name} ({args.model} model), {steps} steps, {total:.2f} s of motion and settling, "
          f"{result.throughput or float('nan'):.1f} steps per hour")
    print(f"fixed-time run of the same moves (Simulator.run of the chained profiles): {t_fixed * 1e3:8.1f} ms"
          "   (baseline)")
    print(f"run_sequence, event-driven:                                              {t_seq * 1e3:8.1f} ms"
          f"   x{t_seq / t_fixed:.2f} of the fixed-time run (target: <= 1.20; under 500 ms)")


if __name__ == "__main__":
    main()
