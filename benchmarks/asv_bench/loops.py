"""A calibration and a closed-loop run, as the scripts ``bench_calibration.py`` and ``bench_closed_loop.py``
time them (their cases are built by those scripts' own functions)."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the benchmark scripts beside this folder


class Calibration:
    """The six isolator parameters of the calibration example fitted to a 7 s move record."""

    repeat = (2, 3, 30.0)
    number = 1
    warmup_time = 0.0
    timeout = 300

    def setup(self) -> None:
        from bench_calibration import move_case

        from isolator.calibration import calibrate

        self.folder = tempfile.TemporaryDirectory()
        self.calibrate = calibrate
        self.path = move_case(Path(self.folder.name))
        calibrate(self.path)  # compiles the model and the stepper

    def teardown(self) -> None:
        self.folder.cleanup()

    def time_calibrate_move(self) -> None:
        self.calibrate(self.path)


class ClosedLoop:
    """A 7 s run of the geophone table with a 36-state exported controller at 2 kHz in the compiled loop."""

    repeat = (3, 10, 20.0)
    number = 1
    warmup_time = 0.0
    timeout = 300

    def setup(self) -> None:
        from bench_closed_loop import controller, scenario

        from isolator import Simulator

        s = scenario()
        self.sim = Simulator(s)
        self.controller = controller(s)
        self.sim.run(controller=self.controller)  # builds and compiles the loop

    def time_closed_loop(self) -> None:
        self.sim.run(controller=self.controller)
