"""Speed of the error budget (issue 32) against ``isolator transmissibility`` on the same scenario.

Two budgets: the passive active-table case (``paper-table-3-2-active``, carriages at their start) with two
points and ten sources (the floor at VC-C on x, y, z; three force disturbances; the noise of four actuators),
and the closed loop of ``paper-table-3-2-geophones`` with the floor at VC-C and the exported controller of
``isolator controller --method lqg --sample-rate 2000 --schedule 3`` (15 sources: the floor's three axes and
the twelve geophones' noise). Baseline, in the same run and on the same scenario: what ``isolator
transmissibility`` computes (``linearise`` + the 6x6 ``transmissibility`` at its 1000 default frequencies).
Run:  ``python benchmarks/bench_budget.py [--repeat N]``
"""

from __future__ import annotations

import argparse
import sys
import time
import tomllib
from pathlib import Path
from typing import cast

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import timed

from controllers.feedback import design_controller
from isolator import scenario_from_dict
from isolator.analysis.budget import ErrorBudget, error_budget
from isolator.analysis.linear import linearise
from isolator.analysis.transmissibility import default_frequencies, transmissibility
from isolator.scenario.reader import bundled_scenarios

POINTS = [{"name": "probe", "position": [0.6, 0.3, 0.5]}, {"name": "lens", "position": [-0.4, 0.0, 0.45]}]


def _data(name: str) -> dict:
    data = tomllib.loads(Path(bundled_scenarios()[name]).read_text())
    data["points"] = POINTS
    data["ground"] = {"spectrum": {"vc": "VC-C"}}
    return data


def passive():  # type: ignore[no-untyped-def]
    """Ten sources: floor:x, y, z, three forces, four actuators' noise."""
    data = _data("paper-table-3-2-active")
    data["disturbances"] = [
        {"name": "acoustic-z", "position": [0.0, 0.0, 0.15], "direction": [0.0, 0.0, 1.0], "psd": 1e-4},
        {"name": "fan-x", "position": [1.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0],
         "psd": {"frequency": [10.0, 50.0, 200.0], "value": [1e-3, 1e-2, 1e-5]}},
        {"name": "cable-y", "position": [-0.8, 0.4, 0.15], "direction": [0.0, 1.0, 0.0], "psd": 4e-5},
    ]
    for act in data["actuators"][:4]:
        act["noise_psd"] = {"frequency": [1.0, 100.0, 1000.0], "value": [1e-4, 1e-6, 1e-6]}
    return scenario_from_dict(data)


def closed():  # type: ignore[no-untyped-def]
    """The geophone table at VC-C and its lqg controller (scheduled over the x-stage at three points)."""
    scenario = scenario_from_dict(_data("paper-table-3-2-geophones"))
    return scenario, design_controller(scenario, "lqg", 2000.0, schedule=3)


def baseline(scenario) -> float:  # type: ignore[no-untyped-def]
    """One ``isolator transmissibility``: linearise, the default 1000 frequencies, the 6x6 response."""
    lin = linearise(scenario)
    return float(transmissibility(lin, default_frequencies(lin, 1000)).response.size)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()
    s_passive = passive()
    s_closed, ctrl = closed()
    t0 = time.perf_counter()
    error_budget(s_passive)
    first = time.perf_counter() - t0
    print(f"first budget (casadi Jacobians built):                    {first * 1e3:8.1f} ms")
    for label, scenario, controller in (("passive, 2 points, 10 sources", s_passive, None),
                                        (f"closed loop ({ctrl.method}, {ctrl.sample_rate:g} Hz), 2 points, "
                                         "15 sources", s_closed, ctrl)):
        t_base, _ = timed(lambda scenario=scenario: baseline(scenario), args.repeat)
        t_budget, result = timed(lambda scenario=scenario, controller=controller: error_budget(scenario, controller),
                                 args.repeat)
        budget = cast(ErrorBudget, result)
        lin = linearise(scenario)
        t_only, _ = timed(lambda lin=lin, controller=controller: error_budget(lin, controller), args.repeat)
        assert len(budget.sources) == (10 if controller is None else 15), budget.sources
        values = ", ".join(f"{p}:{a} {budget.value(p, a) * 1e9:.3g}" for p in budget.points for a in "xyz")
        print(f"{label}: {budget.frequency.size} frequencies, band {budget.band[0]:g}-{budget.band[1]:g} Hz")
        print(f"  RMS displacement [nm]: {values}")
        print(f"  baseline linearise + transmissibility (1000 freq.), median: {t_base * 1e3:8.1f} ms")
        print(f"  error_budget from the scenario, median:                    {t_budget * 1e3:8.1f} ms   "
              f"ratio {t_budget / t_base:5.1f}x the baseline")
        print(f"  error_budget of a linearised model, median:                {t_only * 1e3:8.1f} ms")


if __name__ == "__main__":
    main()
