"""Speed of a top that bends: one 3 s transient of Table 3.2's table with its top's elastic modes, side by side
with the same table on a rigid top (the baseline, measured in the same run).

The bundled ``paper-table-3-2-flexible`` (a 2 x 1 x 0.3 m granite top, modes 188 to 1220 Hz) with a short move
(0.2 m, over by 1.9 s), 3 s long; the top keeping its lowest ``N`` elastic modes for each ``--modes N``, its modes
quasi-static (the default, ``elastic="auto"``: they are 60 times above the table's motion) and, with
``--dynamic``, in the state too. Each figure is the median wall time of ``--repeat`` runs after a first
(compiling) one, whose time is printed too.
Run:  python benchmarks/bench_flexible.py [--modes 6 20] [--repeat 3] [--dynamic]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import timed

from isolator import Simulator, load_scenario
from isolator.scenario.definitions import Table
from isolator.scenario.flexible import load_flexible
from isolator.scenario.profile_shapes import trapezoid


def short_move(modes: int | None) -> object:
    """Table 3.2's flexible scenario with a 0.2 m move of the x stage, 3 s long; ``modes`` elastic modes kept
    (None: a rigid top)."""
    scenario = load_scenario("paper-table-3-2-flexible")
    x, y = scenario.carriages
    moves = (dataclasses.replace(x, profile=trapezoid(start=-0.1, stroke=0.2, velocity=0.2, acceleration=0.5,
                                                      t0=0.5)),
             dataclasses.replace(y, profile=trapezoid(start=0.0, stroke=0.05, velocity=0.1, acceleration=0.5,
                                                      t0=0.5)))
    table = scenario.table
    top = None if modes is None else load_flexible(table.flexible.data.path, thickness=table.size[2], count=modes)
    return dataclasses.replace(scenario, carriages=moves, table=Table(table.mass, table.inertia, table.size, top),
                               simulation=dataclasses.replace(scenario.simulation, duration=3.0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--modes", type=int, nargs="+", default=[6, 20])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--dynamic", action="store_true", help="also run the modes in the state (slow)")
    args = parser.parse_args()
    rows = []
    cases = [(None, "auto")] + [(m, e) for m in args.modes for e in (("auto", "dynamic") if args.dynamic
                                                                        else ("auto",))]
    for modes, elastic in cases:
        simulator = Simulator(short_move(modes), elastic=elastic)
        start = time.perf_counter()
        simulator.run()
        first = time.perf_counter() - start
        warm, response = timed(simulator.run, args.repeat)
        rows.append((modes, elastic, first, warm, response.settling_time_max))
    rigid = rows[0][3]
    print("3 s transient of Table 3.2's table (0.2 m move), median of warm runs; the first run compiles")
    for modes, elastic, first, warm, settling in rows:
        label = "rigid top (baseline)" if modes is None else f"{modes} modes, " + (
            "quasi-static" if elastic == "auto" else "dynamic")
        settled = "unsettled" if settling is None else f"{settling:.6g} s"
        print(f"{label:26s} first {first:8.2f} s   warm {warm * 1e3:10.2f} ms   ratio {warm / rigid:8.1f}x   "
              f"settling {settled}")


if __name__ == "__main__":
    main()
