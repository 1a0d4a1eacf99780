"""The numbers the speed work (issue 36) must not change: batches, a sweep, single runs and the free-motion
verdicts on the bundled scenarios, computed the same way by the reference file's writer (``python
tests/speed_reference.py``, run once on the code before the speed work) and by the tests
(``test_speed_reference.py``), which compare them."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from isolator import Simulator, load_scenario
from isolator.scenario.definitions import SIGNALS
from isolator.simulation.tail_check import run_tail
from isolator.sweep import sweep

#: the stored numbers (written by this module's ``main``)
REFERENCE = Path(__file__).parent / "simulation" / "data" / "speed_reference.npz"
#: every isolator's damping giving a mode at zeta 0.97 (the free-tail tests' heavy design)
HEAVY = {f"isolators[{i}].damping.{a}": 52500.0 for i in range(4) for a in "xyz"}
#: single runs: (scenario, model, duration or None, changes or None)
SINGLE = (
    ("paper-table-3-1", "exact", None, None),
    ("paper-table-3-2", "exact", None, None),
    ("paper-table-3-2", "paper", None, None),
    ("paper-table-3-2", "exact", 9.0, None),
    ("paper-table-3-2", "exact", 10.0, None),
    ("paper-table-3-2", "exact", None, HEAVY),
    ("paper-table-3-2-pneumatic", "exact", 12.0, None),
    ("paper-table-3-2-pneumatic-3", "exact", 12.0, None),
)


def _scenario(name: str, duration: float | None):
    scenario = load_scenario(name)
    if duration is None:
        return scenario
    return dataclasses.replace(scenario, simulation=dataclasses.replace(scenario.simulation, duration=duration))


def _batch(out: dict[str, np.ndarray], key: str, sim: Simulator, k: np.ndarray, c: np.ndarray) -> None:
    result = sim.run_batch(k, c, workers=2, diverged="record")
    out[f"{key}/settling"] = result.settling_time
    out[f"{key}/peak"] = result.peak
    out[f"{key}/half_widths"] = result.half_widths
    out[f"{key}/status"] = result.status.astype(str)
    out[f"{key}/reason"] = np.array([result.reason(i) for i in range(len(k))], dtype=str)


def compute() -> dict[str, np.ndarray]:
    """Every number the reference holds, by key."""
    out: dict[str, np.ndarray] = {}
    rng = np.random.default_rng(1)
    k, c = rng.uniform(0.5, 2.0, 1000), rng.uniform(0.5, 4.0, 1000)
    _batch(out, "batch", Simulator(load_scenario("paper-table-3-2")), k, c)
    _batch(out, "batch-paper", Simulator(load_scenario("paper-table-3-2"), "paper"), k[:64], c[:64])
    _batch(out, "batch-short", Simulator(_scenario("paper-table-3-2", 9.0)), k[:64], c[:64])
    _batch(out, "batch-pneumatic", Simulator(_scenario("paper-table-3-2-pneumatic", 12.0)), k[:8], c[:8])
    for n, (name, model, duration, changes) in enumerate(SINGLE):
        run = Simulator(_scenario(name, duration), model).run(changes)
        key = f"single{n}"
        out[f"{key}/settling"] = np.array([np.nan if run.settling[s].time is None else run.settling[s].time
                                           for s in SIGNALS])
        out[f"{key}/peak"] = np.array([run.settling[s].peak for s in SIGNALS])
        out[f"{key}/band"] = np.array([run.settling[s].band for s in SIGNALS])
        out[f"{key}/reason"] = np.array([run.settling[s].reason for s in SIGNALS], dtype=str)
        out[f"{key}/signals"] = run.signals[:, ::100]  # every 100th sample: small
        sim = Simulator(_scenario(name, duration), model)
        p = sim.parameter_vector(changes)
        start, end = sim.equilibria(p)
        tail, _ = run_tail(sim.scenario, sim.model, p, start, end, run.states[-1], float(run.t[-1]))
        if tail is not None:
            verdict = tail.judge(np.array([run.settling[s].band for s in SIGNALS]))
            for field in ("leaves", "excess", "when", "enters", "offset"):
                out[f"{key}/verdict/{field}"] = np.asarray(getattr(verdict, field))
    swept = sweep("paper-table-3-2", scale={"isolators[*].stiffness": (0.5, 2.0), "isolators[*].damping": (0.3, 4.0)},
                  samples=256, seed=3, workers=1)
    for column in swept.columns:
        values = swept[column]
        out[f"sweep/{column}"] = values.astype(str) if values.dtype == object else values
    return out


def main() -> None:
    REFERENCE.parent.mkdir(exist_ok=True)
    np.savez_compressed(REFERENCE, **compute())
    print(f"wrote {REFERENCE}")


if __name__ == "__main__":
    main()
