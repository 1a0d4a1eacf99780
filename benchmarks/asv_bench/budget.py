"""The error budget (``isolator.analysis.budget``), as ``bench_budget.py`` times it: the passive active
table (two points, ten sources) and the geophone table's closed loop with its lqg controller (15 sources).
A commit without the budget skips these (``NotImplementedError`` in ``setup``, asv's way to skip)."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the benchmark scripts beside this folder


class Budget:
    """``error_budget(scenario, controller)`` from the scenario (linearisation included)."""

    params = ("passive", "closed loop")
    param_names = ("case",)
    repeat = (3, 10, 20.0)
    number = 1
    warmup_time = 0.0
    timeout = 300

    def setup(self, case: str) -> None:
        try:
            from bench_budget import closed, passive

            from isolator.analysis.budget import error_budget
        except ImportError as exc:  # a commit before the error budget
            raise NotImplementedError(f"no error budget here: {exc}") from None
        self.error_budget = error_budget
        self.scenario, self.controller = (passive(), None) if case == "passive" else closed()
        error_budget(self.scenario, self.controller)  # builds the Jacobians

    def time_budget(self, case: str) -> None:
        self.error_budget(self.scenario, self.controller)
