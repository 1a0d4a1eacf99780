"""Speed of the profile optimisation on the paper's Table 3.2 scenario.

Prints each figure and its ratio to a baseline measured in the same run, one
simulation of the scenario (12 s, exact model):

* the first optimisation in an empty model cache (the RK4 step and its
  derivatives are compiled once per scenario structure, then cached on disk);
* the optimisation with the cache warm: nominal model, single and multiple
  shooting; and over the seven model variants (the command's default).

Each optimisation includes screening, IPOPT and the verifying simulation.
Target: under 10 s.

Run:  python benchmarks/bench_profiles.py
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import timed

from controllers.profiles import ROBUSTNESS_VARIANTS, ModelVariant, ProfileSettings, optimise_profiles
from isolator import Simulator, load_scenario


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    scenario = load_scenario("paper-table-3-2")
    sim = Simulator(scenario)
    sim.run()
    t_sim, _ = timed(sim.run, args.repeat)
    nominal = ProfileSettings(variants=(ModelVariant(),))
    previous = os.environ.get("ISOLATOR_CACHE")
    with tempfile.TemporaryDirectory() as empty:
        os.environ["ISOLATOR_CACHE"] = empty
        start = time.perf_counter()
        optimise_profiles(scenario, nominal)
        t_cold = time.perf_counter() - start
    if previous is None:
        del os.environ["ISOLATOR_CACHE"]
    else:
        os.environ["ISOLATOR_CACHE"] = previous
    optimise_profiles(scenario, nominal)  # the step compiled into the default cache
    rows = [("one simulation (baseline)", t_sim, None)]
    rows.append(("optimisation, empty cache (compiles)", t_cold, None))
    for label, settings in (
        ("optimisation, nominal, single shooting", nominal),
        ("optimisation, nominal, multiple shooting", ProfileSettings(variants=(ModelVariant(),),
                                                                     transcription="multiple")),
        ("optimisation, 7 model variants (default)", ProfileSettings(variants=ROBUSTNESS_VARIANTS)),
    ):
        t, result = timed(lambda s=settings: optimise_profiles(scenario, s), args.repeat)
        rows.append((label, t, result))
    print(f"{'':44} {'time [s]':>9} {'x one simulation':>17}  result")
    for label, t, result in rows:
        extra = ""
        if result is not None:
            extra = (f"settling {result.optimised.settling_time_max:.3f} s, move {result.optimised.move_time:.3f} s, "
                     f"{result.iterations} iterations")
        print(f"{label:44} {t:9.2f} {t / t_sim:17.0f}  {extra}")


if __name__ == "__main__":
    main()
