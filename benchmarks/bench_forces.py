"""``isolator simulate --forces`` and ``--controller`` on the geophone table (issue 43 item 2): twelve actuators
with a 200 Hz lag, end to end (a fresh process each, the compiled-model cache warm) and the run alone in one
process.

    python benchmarks/bench_forces.py              # --repeat 5
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SCENARIO = "paper-table-3-2-geophones"


def forces_table(duration: float = 12.0, names: tuple[str, ...] | None = None) -> tuple[np.ndarray, np.ndarray,
                                                                                        tuple[str, ...]]:
    """Times [s], forces (actuators, samples) [N] and names: a 7 Hz sine on z1, a 3 Hz one on x2 clipped at its
    500 N, a 200 N step on y3 at 2 s, sampled at 1 ms."""
    names = names or tuple(f"{axis}{i}" for i in range(1, 5) for axis in "xyz")
    t = np.arange(0.0, duration + 5e-4, 1e-3)
    forces = np.zeros((len(names), t.size))
    forces[names.index("z1")] = 300.0 * np.sin(2 * np.pi * 7.0 * t)
    forces[names.index("x2")] = 700.0 * np.sin(2 * np.pi * 3.0 * t + 0.3)
    forces[names.index("y3")] = np.where(t >= 2.0, 200.0, 0.0)
    return t, forces, names


def write_forces(path: Path) -> Path:
    """The forces file of :func:`forces_table` (``t`` and one column per actuator) [s, N]."""
    t, forces, names = forces_table()
    np.savetxt(path, np.column_stack([t, forces.T]), delimiter=",", header=",".join(["t", *names]), comments="",
               fmt="%.10g")
    return path


def history():  # type: ignore[no-untyped-def]
    """The scenario and the same forces as a ``ForceHistory``, for a run in this process."""
    from isolator import load_scenario
    from isolator.simulation.actuation import ForceHistory

    scenario = load_scenario(SCENARIO)
    t, forces, names = forces_table(names=tuple(a.name for a in scenario.actuators))
    return scenario, ForceHistory(t, forces, names)


def command(extra: list[str], cwd: Path) -> float:
    """Wall time [s] of ``isolator simulate SCENARIO --json`` with ``extra``, in a fresh process."""
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "isolator.cli", "simulate", SCENARIO, "--json", *extra], check=True,
                   stdout=subprocess.DEVNULL, cwd=cwd)
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    from isolator import Simulator

    scenario, forces = history()
    sim = Simulator(scenario)
    sim.run(forces=forces)
    runs = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        sim.run(forces=forces)
        runs.append(time.perf_counter() - t0)
    with tempfile.TemporaryDirectory() as tmp:
        path = write_forces(Path(tmp) / "forces.csv")
        command(["--forces", str(path)], Path(tmp))  # warms the cache
        ends = [command(["--forces", str(path)], Path(tmp)) for _ in range(args.repeat)]
    print(f"the forced run in this process: median {1e3 * statistics.median(runs):.1f} ms")
    print(f"isolator simulate --forces, end to end: median {statistics.median(ends):.2f} s")


if __name__ == "__main__":
    main()
