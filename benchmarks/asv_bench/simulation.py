"""One transient, a batch and a sweep of the paper's Table 3.2 case (12 s at 1 kHz, exact model)."""

from __future__ import annotations

import numpy as np

from isolator import Simulator, load_scenario


def _factors(runs: int) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness x0.5-2 and damping x0.5-4 per run (the batch figure of benchmarks/README.md)."""
    rng = np.random.default_rng(1)
    return rng.uniform(0.5, 2.0, runs), rng.uniform(0.5, 4.0, runs)


class Transient:
    """One 12 s run (equilibria, stepping, metrics and the free-motion judgement)."""

    repeat = (3, 20, 20.0)
    number = 5
    warmup_time = 0.5

    def setup(self) -> None:
        self.sim = Simulator(load_scenario("paper-table-3-2"))
        self.sim.run()

    def time_run(self) -> None:
        self.sim.run()


class Batch:
    """1,000 runs with every isolator's stiffness and damping scaled, one thread."""

    repeat = (2, 5, 30.0)
    number = 1
    warmup_time = 0.0
    timeout = 300

    def setup(self) -> None:
        self.sim = Simulator(load_scenario("paper-table-3-2"))
        self.k, self.c = _factors(1000)
        self.sim.run_batch(self.k[:100], self.c[:100], workers=1)  # compiles the four-lane loop

    def time_batch(self) -> None:
        self.sim.run_batch(self.k, self.c, workers=1)


class Sweep:
    """``isolator.sweep.sweep`` of 2,000 Sobol designs over stiffness and damping, in this process."""

    repeat = (2, 3, 30.0)
    number = 1
    warmup_time = 0.0
    timeout = 300

    def setup(self) -> None:
        from isolator.sweep import sweep

        self.sweep = sweep
        self.scale = {"isolators[*].stiffness": (0.5, 2.0), "isolators[*].damping": (0.5, 4.0)}
        sweep("paper-table-3-2", scale=self.scale, samples=64, workers=1)  # builds the worker's simulator

    def time_sweep(self) -> None:
        self.sweep("paper-table-3-2", scale=self.scale, samples=2000, workers=1)


class Forced:
    """The geophone table's 12 s run with a forces file's commands on its twelve lagged actuators (issue 43: the
    lags at no cost), in this process, as ``isolator simulate --forces`` runs it."""

    repeat = (3, 10, 20.0)
    number = 1
    warmup_time = 0.0
    timeout = 300

    def setup(self) -> None:
        import sys
        from pathlib import Path

        sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the benchmark scripts beside this folder
        from bench_forces import history

        scenario, self.forces = history()
        self.sim = Simulator(scenario)
        self.sim.run(forces=self.forces)  # compiles the stepper

    def time_forced_run(self) -> None:
        self.sim.run(forces=self.forces)
