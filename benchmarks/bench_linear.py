"""Speed of the linear analyses on the paper's Table 3.2 case.

Prints each figure and its ratio to a baseline measured in the same run:
python-control's own frequency response of the same 12-state system
(``StateSpace.frequency_response``). Run:  python benchmarks/bench_linear.py
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import timed

from isolator import load_scenario
from isolator.analysis.linear import GROUND_INPUTS, linearise
from isolator.analysis.modes import modes
from isolator.analysis.transmissibility import transmissibility


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=20)
    parser.add_argument("--frequencies", type=int, default=1000)
    args = parser.parse_args()
    sc = load_scenario("paper-table-3-2")
    t0 = time.perf_counter()
    lin = linearise(sc)
    first = time.perf_counter() - t0
    t_lin, lin = timed(lambda: linearise(sc), args.repeat)
    f = np.logspace(-1, 2, args.frequencies)
    t_tr, tr = timed(lambda: transmissibility(lin, f), args.repeat)
    t_all, _ = timed(lambda: transmissibility(linearise(sc), f), args.repeat)
    t_modes, _ = timed(lambda: modes(lin), args.repeat)
    sub = lin.system[list(range(6)), list(range(6))]  # ground inputs -> table signals
    t_ctrl, resp = timed(lambda: sub.frequency_response(2 * np.pi * f), max(3, args.repeat // 4))
    ref = np.moveaxis(np.asarray(resp.complex), -1, 0)
    err = float(np.max(np.abs(ref - tr.response)) / np.max(np.abs(ref)))
    assert list(sub.input_labels) == list(GROUND_INPUTS)
    print(f"linearise, first call (casadi Jacobians built):          {first * 1e3:8.2f} ms")
    print(f"linearise, equilibrium + Jacobians + state space (median): {t_lin * 1e3:8.2f} ms")
    print(f"modes (median):                                          {t_modes * 1e3:8.2f} ms")
    print(f"6x6 transmissibility at {f.size} frequencies (median):     {t_tr * 1e3:8.2f} ms")
    print(f"  ... including the linearisation (median):              {t_all * 1e3:8.2f} ms")
    print(f"baseline python-control StateSpace.frequency_response:   {t_ctrl * 1e3:8.2f} ms   "
          f"ratio {t_ctrl / t_tr:6.1f}x slower   (max rel. difference {err:.1e})")


if __name__ == "__main__":
    main()
