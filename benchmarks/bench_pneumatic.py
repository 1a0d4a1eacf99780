"""Speed of pneumatic transients against the spring-damper ones, side by side in one run.

The paper's Table 3.2 table and stage, 12 s at 1 kHz, exact model: the
spring-damper scenario (``paper-table-3-2``) is the baseline; the pneumatic one
(``paper-table-3-2-pneumatic``, valves on, its duration set to the same 12 s)
adds 8 chamber pressures as states, the valves' dead zones and the leveling
results. Also timed: the pneumatic results computed on first use (pressures,
heights, leveling times and the quasi-static pose for the settling about the
leveling table), and an accuracy check against a run with steps a quarter as
long. Run:  python benchmarks/bench_pneumatic.py [--repeat N]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import timed

import isolator.simulation.simulator as simmod
from isolator import Simulator, load_scenario


def _twelve_seconds(name: str):
    scenario = load_scenario(name)
    return replace(scenario, simulation=replace(scenario.simulation, duration=12.0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=30)
    args = parser.parse_args()

    spring = Simulator(_twelve_seconds("paper-table-3-2"))
    pneumatic = Simulator(_twelve_seconds("paper-table-3-2-pneumatic"))
    spring.run(), pneumatic.run().pneumatic  # compile and warm both
    t_spring, _ = timed(lambda: spring.run(), args.repeat)
    t_pneu, run = timed(lambda: pneumatic.run(), args.repeat)
    t_results, _ = timed(lambda: pneumatic.run().pneumatic, max(3, args.repeat // 3))
    start, end = pneumatic.equilibria(pneumatic.parameters)
    method = pneumatic.method_for(max(start.max_frequency, end.max_frequency if end else 0.0))
    base = spring.method_for(max(e.max_frequency for e in spring.equilibria(spring.parameters) if e is not None))
    print(f"spring-damper, 12 s at 1 kHz ({base.plan.steps if base.plan else '-'} DOP853 steps):"
          f"         median {1e3 * t_spring:7.2f} ms")
    print(f"pneumatic, valves on, 12 s at 1 kHz ({method.plan.steps if method.plan else '-'} DOP853 steps, "
          f"{pneumatic.model.n_states} states): median {1e3 * t_pneu:7.2f} ms   ratio {t_pneu / t_spring:5.2f}x")
    print(f"pneumatic run + its leveling results (pressures, heights, quasi-static pose):"
          f"  median {1e3 * t_results:7.2f} ms   ratio {t_results / t_spring:5.2f}x")

    # accuracy: the same run with DOP853 steps a quarter as long
    saved = simmod.DENSE_STEP_ANGLE
    try:
        simmod.DENSE_STEP_ANGLE = saved / 4
        fine = Simulator(_twelve_seconds("paper-table-3-2-pneumatic")).run()
    finally:
        simmod.DENSE_STEP_ANGLE = saved
    assert hasattr(run, "signals")
    err = np.sqrt(np.mean((run.signals - fine.signals) ** 2, axis=1)) / np.sqrt(np.mean(fine.signals**2, axis=1))
    print(f"accuracy vs steps a quarter as long: max rel. RMS {np.max(err):.2e} "
          f"(per signal {', '.join(f'{e:.1e}' for e in err)})")


if __name__ == "__main__":
    main()
