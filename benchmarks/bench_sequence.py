"""Speed of a step-and-settle sequence: the bundled paper-table-3-2-sequence (Table 3.2's table and stages,
a 5 x 4 serpentine grid, +-50 nm probe window, measure 0.1 s: about 90 s of motion and settling).

Prints each figure and its ratio to a baseline measured in the same run: the same moves as a fixed-time
run (each carriage's steps chained into one profile at the start times the sequence found, simulated as an
ordinary scenario by ``Simulator.run``), so the ratio is what the event logic (running each step in chunks
until the window rule is decided, the equilibria per step, the stitching) costs. Both timings include
building the run (``Simulator(...)`` for the fixed-time run; the compiled model is cached for both).

With ``--optimise``: the throughput optimisation of the 20 steps (``isolator optimise-profile``), its wall
time and the throughput it finds against the S-curves at the limits and the ZVD-shaped sequence (both
simulated in the same run).
Run:  python benchmarks/bench_sequence.py [--optimise]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import timed

from isolator import Scenario, Simulator, load_scenario, run_sequence
from isolator.simulation.sequence import chain_scenario


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=20, help="repeats of each timing (median)")
    parser.add_argument("--model", choices=("exact", "paper"), default="exact")
    parser.add_argument("--optimise", action="store_true", help="also time the throughput optimisation")
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
    if args.optimise:
        _optimise(sc, args.model)


def _optimise(sc: Scenario, model: str) -> None:
    from controllers.profiles.sequence_baselines import shaped_moves
    from controllers.profiles.sequence_design import optimise_sequence

    plain = run_sequence(sc, model)
    zvd = run_sequence(sc, model, move=shaped_moves(sc, "zvd"))
    t0 = time.perf_counter()
    opt = optimise_sequence(sc, model)
    wall = time.perf_counter() - t0
    best = opt.after
    print(f"throughput optimisation of the {len(best.steps)} steps: {wall:8.1f} s   (target: under 60 s), "
          f"{opt.evaluations} single-step simulations")
    for label, run in (("S-curves at the limits", plain), ("ZVD-shaped S-curves", zvd)):
        print(f"  against {label:<23}: {run.total_time:7.2f} s -> {best.total_time:7.2f} s, throughput "
              f"{run.throughput:7.1f} -> {best.throughput:7.1f} steps/h (x{best.throughput / run.throughput:.3f})")


if __name__ == "__main__":
    main()
