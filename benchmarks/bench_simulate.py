"""Speed of the transient simulation on the paper's Table 3.2 case (12 s, 1 kHz).

Prints each figure and its ratio to baselines measured in the same run:
a plain numpy + scipy.solve_ivp implementation of the same equations, and
the MuJoCo multibody check. Run:  python benchmarks/bench_simulate.py
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from numpy_reference import NumpyTable
from timing import timed

from isolator import Simulator, load_scenario
from isolator.multibody import MujocoTable, mujoco_available
from isolator.simulation import table_signals
from studies.paper import relative_rms


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--batch", type=int, default=1000, help="runs in the batch figure")
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()
    sc = load_scenario("paper-table-3-2")

    with tempfile.TemporaryDirectory() as cache:
        os.environ["ISOLATOR_CACHE"] = cache
        t0 = time.perf_counter()
        sim = Simulator(sc)
        sim.run()
        cold = time.perf_counter() - t0
    os.environ.pop("ISOLATOR_CACHE")
    import isolator.simulation as simmod

    simmod._MODELS.clear()
    simmod._STEPPERS.clear()
    t0 = time.perf_counter()
    sim = Simulator(sc)
    sim.run()
    warm = time.perf_counter() - t0
    print(f"model build + first run, cold (casadi codegen + C compile): {cold * 1e3:8.1f} ms")
    print(f"model build + first run, warm compiled-model cache:          {warm * 1e3:8.1f} ms")

    t_sim, response = timed(sim.run, args.repeat)
    print(f"simulation, exact model, 12 s at 1 kHz (median of {args.repeat}):  {t_sim * 1e3:8.2f} ms")

    ref_model = NumpyTable(sc)
    _t_ref, (_, states, y0) = timed(lambda: ref_model.simulate(rtol=1e-12, atol=1e-15), 1)
    ref = table_signals(states, y0)
    err = relative_rms(response.signals, ref)
    print(f"accuracy vs tight-tolerance reference (DOP853 rtol 1e-12): max rel. RMS {err.max():.2e} "
          f"(per signal {', '.join(f'{e:.1e}' for e in err)})")

    t_np, (_t, states, y0) = timed(lambda: ref_model.simulate(rtol=1e-8, atol=1e-12), 1)
    sig = table_signals(states, y0)
    print(f"baseline numpy + solve_ivp DOP853 rtol 1e-8 (max rel. RMS {relative_rms(sig, ref).max():.1e}): "
          f"{t_np * 1e3:8.1f} ms   ratio {t_np / t_sim:6.1f}x slower")
    if mujoco_available():
        t_mj, _ = timed(lambda: MujocoTable(sc).simulate(rtol=1e-8, atol=1e-12), 1)
        print(f"baseline MuJoCo check, DOP853 rtol 1e-8:                   {t_mj * 1e3:8.1f} ms   "
              f"ratio {t_mj / t_sim:6.1f}x slower")

    rng = np.random.default_rng(1)
    k = rng.uniform(0.5, 2.0, args.batch)
    c = rng.uniform(0.5, 4.0, args.batch)
    t0 = time.perf_counter()
    sim.run_batch(k[:2], c[:2])  # warm-up: compiles the stepper the batch needs
    t0 = time.perf_counter()
    batch = sim.run_batch(k, c, workers=2)
    t_batch = time.perf_counter() - t0
    ok = np.isfinite(batch.settling_time_max).sum()
    print(f"batch, {args.batch} runs, stiffness x0.5-2, damping x0.5-4, 2 threads: {t_batch:6.2f} s = "
          f"{args.batch / t_batch:6.0f} runs/s  (single-run rate {1 / t_sim:5.0f} runs/s; "
          f"{ok} runs with a settling time)")


if __name__ == "__main__":
    main()
