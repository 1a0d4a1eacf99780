"""Sweeps over parameters the model's time-only part depends on (a carriage's mass, a carriage's position on
the table, the table's mass and inertia) against a sweep over stiffness, in the same run (issue 26, item 5).

Every sweep runs the same number of designs of the paper's Table 3.2 case (12 s, 1 kHz) through
``isolator.sweep.sweep`` in this process (``workers=1``: one core, one chunk after another), each swept name
scaled by factors drawn in [0.5, 2]; each figure is the median of ``--repeat`` sweeps and is given as a ratio
to the stiffness sweep's. Run:  python benchmarks/bench_any_parameter.py [--runs 400] [--repeat 3]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import timed

from isolator.sweep import sweep

SCENARIO = "paper-table-3-2"
#: the swept names; the first is the baseline
SWEEPS = {
    "stiffness (isolators[*].stiffness)": "isolators[*].stiffness",
    "carriage mass (carriages[0].mass)": "carriages[0].mass",
    "carriage position (carriages[0].origin)": "carriages[0].origin",
    "table mass (table.mass)": "table.mass",
    "table inertia (table.inertia)": "table.inertia",
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=400, help="designs per sweep")
    parser.add_argument("--repeat", type=int, default=3, help="sweeps per figure (the median is shown)")
    args = parser.parse_args()
    factors = np.random.default_rng(1).uniform(0.5, 2.0, args.runs)
    base = None
    for label, name in SWEEPS.items():
        values = {name: factors}
        sweep(SCENARIO, scale={name: factors[:16]}, workers=1)  # warm: its steppers compiled, its plans made
        dt, result = timed(lambda values=values: sweep(SCENARIO, scale=values, workers=1), args.repeat)
        rate = args.runs / dt
        base = rate if base is None else base
        print(f"{label:<42} {args.runs} designs, 1 process: {rate:7.0f} runs/s (median of {args.repeat})   "
              f"{base / rate:5.2f}x the stiffness sweep's time; {result.tally.failed} not ok")  # type: ignore[attr-defined]


if __name__ == "__main__":
    main()
