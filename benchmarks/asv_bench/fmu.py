"""The plant FMUs' Co-Simulation ``doStep`` loop in FMPy (issue 43), as ``bench_fmu.py`` times it: 7 s at 1 ms
of the passive table and of the geophone table (twelve actuators with a 200 Hz lag)."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the benchmark scripts beside this folder


class DoStep:
    """Seven seconds of 1 ms ``doStep`` calls, initialisation not counted."""

    params = ("paper-table-3-2", "paper-table-3-2-geophones")
    param_names = ("table",)
    repeat = (3, 5, 30.0)
    number = 1
    warmup_time = 0.0
    timeout = 300

    def setup(self, table: str) -> None:
        try:
            import fmpy  # noqa: F401
        except ImportError as exc:
            raise NotImplementedError(f"no FMPy: {exc}") from None
        from bench_fmu import build

        self.folder = tempfile.TemporaryDirectory()
        self.path = build(table, Path(self.folder.name))
        self.rounds = 0

    def teardown(self, table: str) -> None:
        self.folder.cleanup()

    def time_do_step(self, table: str) -> None:
        from bench_fmu import do_steps

        self.rounds += 1
        do_steps(self.path, 7.0, Path(self.folder.name) / f"unzip-{self.rounds}", False)
