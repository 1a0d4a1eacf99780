"""Shared scenario builders for the tests, and how the test modules reach them.

The tests mirror the packages: ``tests/scenario``, ``model``, ``numerics``,
``simulation``, ``analysis``, ``validation``, ``cli`` for the plant,
``tests/controllers`` and ``tests/studies``; ``tests/properties`` holds the
property-based tests (hypothesis: the "ci" profile below by default, many
more examples with ``HYPOTHESIS_PROFILE=thorough``); ``test_style.py`` stays here. No
folder of tests has an ``__init__.py``, on purpose: in pytest's default
("prepend") import mode, loading this conftest puts ``tests/`` on
``sys.path``, and importing a test module puts its own folder there. Hence:

- the builders below are imported as a plain module from any subfolder,
  ``from conftest import base_dict, make`` (and so are the helper modules
  next to this file, e.g. ``from pneumatic_cases import ...``); the ``base``
  fixture gives ``base_dict()``;
- test modules are imported by their file name alone, so two test files must
  not share a name, even in different folders (pytest would stop with
  "import file mismatch"); name a new one after what it tests
  (``tests/scenario/test_validation.py``, not ``tests/scenario/test_scenario.py``
  next to a ``tests/model/test_scenario.py``).
"""

from __future__ import annotations

import copy
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

from isolator import Scenario, scenario_from_dict

# property-based tests (tests/properties): few examples in CI, many with HYPOTHESIS_PROFILE=thorough
settings.register_profile("ci", max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("thorough", max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """Workers for ``-n auto`` (pyproject's addopts): one per core this process may use, at most four (each
    worker compiles and holds its own models); ``PYTEST_XDIST_AUTO_NUM_WORKERS`` decides when set."""
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return int(os.environ["PYTEST_XDIST_AUTO_NUM_WORKERS"])
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    return max(1, min(cores, 4))


# no "compiling the model ..." line on stderr: tests count the command's stderr lines (subprocesses inherit it)
os.environ.setdefault("ISOLATOR_QUIET", "1")


def corner_isolators(k: float = 5.7e5, c: float = 5.7e3, hs: float = 0.15) -> list[dict[str, Any]]:
    """Four identical isolators under the corners of a 2 m x 1 m table."""
    return [
        {"position": [x, y, -hs], "stiffness": [k, k, k], "damping": [c, c, c]}
        for x, y in ((1.0, 0.5), (-1.0, 0.5), (-1.0, -0.5), (1.0, -0.5))
    ]


def base_dict(**overrides: Any) -> dict[str, Any]:
    """A valid scenario as a dictionary: one carriage on a symmetric table."""
    data: dict[str, Any] = {
        "name": "test",
        "table": {"mass": 4400.0, "size": [2.0, 1.0, 0.3]},
        "isolators": corner_isolators(),
        "carriages": [
            {
                "name": "x-stage",
                "mass": 400.0,
                "parent": "table",
                "axis": [1.0, 0.0, 0.0],
                "origin": [0.0, 0.0, 0.35],
                "profile": {"type": "scurve", "start": -0.4, "stroke": 0.8, "velocity": 0.4,
                            "acceleration": 1.0, "jerk": 20.0, "t0": 0.2},
            }
        ],
        "simulation": {"duration": 4.0, "sample_rate": 1000.0},
    }
    data.update(overrides)
    return data


def active_dict(max_force: float = 500.0, bandwidth: float | None = None) -> dict[str, Any]:
    """:func:`base_dict` made active: three actuators (x, y, z) at each isolator, 3 s long."""
    data = base_dict()
    data["simulation"]["duration"] = 3.0
    acts = []
    for k, iso in enumerate(data["isolators"]):
        for axis, d in (("x", [1.0, 0, 0]), ("y", [0, 1.0, 0]), ("z", [0, 0, 1.0])):
            act = {"name": f"{axis}{k}", "position": iso["position"], "direction": d, "max_force": max_force}
            if bandwidth is not None:
                act["bandwidth"] = bandwidth
            acts.append(act)
    data["actuators"] = acts
    return data


def tipping_dict(height: float) -> dict[str, Any]:
    """The base table without carriages, 4400 kg, its isolators ``height`` [m] below the mass centre (the
    hand-calculated tipping cases: rocking stiffness against weight times height)."""
    data = base_dict()
    data["carriages"] = []
    data["table"] = {"mass": 4400.0, "inertia": [400.0, 1500.0, 1800.0]}
    for iso in data["isolators"]:
        iso["position"][2] = -height
    return data


def make(data: dict[str, Any]) -> Scenario:
    return scenario_from_dict(copy.deepcopy(data))


def asymmetric_3d_dict(duration: float = 5.0) -> dict[str, Any]:
    """Two stacked carriages on skewed axes over five unequal, scattered isolators."""
    return {
        "name": "asymmetric-3d",
        "table": {"mass": 2500.0, "inertia": [400.0, 900.0, 1100.0], "size": [2.4, 1.6, 0.3]},
        "isolators": [
            {"position": [1.1, 0.7, -0.20], "stiffness": [3e5, 4e5, 6e5], "damping": [3e3, 2e3, 5e3]},
            {"position": [-0.9, 0.6, -0.15], "stiffness": [4e5, 3e5, 5e5], "damping": [4e3, 3e3, 4e3]},
            {"position": [-1.0, -0.7, -0.18], "stiffness": [3.5e5, 3.5e5, 7e5], "damping": [2e3, 4e3, 6e3]},
            {"position": [0.8, -0.6, -0.12], "stiffness": [5e5, 2e5, 4e5], "damping": [5e3, 1e3, 3e3]},
            {"position": [0.1, 0.05, -0.25], "stiffness": [1e5, 1e5, 2e5], "damping": [1e3, 1e3, 1e3]},
        ],
        "carriages": [
            {
                "name": "lower",
                "mass": 300.0,
                "axis": [0.8, 0.6, 0.0],
                "origin": [0.1, -0.05, 0.25],
                "profile": {"type": "scurve", "start": -0.3, "stroke": 0.7, "velocity": 0.5,
                            "acceleration": 2.0, "jerk": 40.0, "t0": 0.1},
            },
            {
                "name": "upper",
                "mass": 60.0,
                "parent": "lower",
                "axis": [0.0, 0.6, 0.8],
                "origin": [0.0, 0.1, 0.2],
                "profile": {"type": "trapezoid", "start": 0.1, "stroke": -0.3, "velocity": 0.3,
                            "acceleration": 1.5, "deceleration": 3.0, "t0": 0.4},
            },
        ],
        "simulation": {"duration": duration, "sample_rate": 1000.0},
    }


@pytest.fixture
def base() -> dict[str, Any]:
    return base_dict()


def same_columns(a: dict[str, Any], b: dict[str, Any], rtol: float = 1e-12) -> None:
    """Two sweeps' columns (``SweepResult.table()``) equal: the same names, text columns identical, numbers
    to ``rtol`` (0: exactly), NaN where NaN."""
    import numpy as np

    assert list(a) == list(b)
    for name in a:
        if a[name].dtype == object:
            assert a[name].tolist() == b[name].tolist(), name
        else:
            np.testing.assert_allclose(a[name], b[name], rtol=rtol, atol=0, equal_nan=True, err_msg=name)


# -- calibration: SYNTHETIC records of a table whose isolators are 15-30 % off the datasheet (the MuJoCo check) --
RECORDS = Path(__file__).parent / "calibration" / "data" / "mujoco-records.npz"


def table_data() -> dict:
    """The calibration example's table (datasheet isolators, nine table and three floor accelerometers)."""
    from isolator.validation.calibration_example import table_data as example

    return example()


def load_records():
    """The noise-free MuJoCo records of the example's true table (``python -m
    isolator.validation.calibration_example DIR --noise-free tests/calibration/data/mujoco-records.npz``)."""
    from isolator.validation.synthetic_records import SyntheticRecord

    data = np.load(RECORDS)
    move = {k.split(":", 1)[1]: data[k] for k in data.files if k.startswith("move:")}
    floor = {k.split(":", 1)[1]: data[k] for k in data.files if k.startswith("floor:")}
    return SyntheticRecord(data["move_t"], move), SyntheticRecord(data["floor_t"], floor)


@pytest.fixture(scope="session")
def mujoco_records():
    """(move, floor): noise-free records of the true table made by the MuJoCo check."""
    return load_records()


@pytest.fixture(scope="session")
def true_values() -> dict:
    """The true table's fitted values by name [SI]."""
    from isolator.validation.calibration_example import true_values as example

    return example()


@pytest.fixture(scope="session")
def write_calibration():
    """``write(folder, move, floor, seed, experiments)``: the example's files with those records and noise seed."""
    from isolator.validation.calibration_example import make_example

    def write(folder: Path, move, floor, seed: int, experiments=("floor", "move")) -> Path:
        return make_example(folder, (move, floor), seed, tuple(experiments))

    return write


def run_command(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, list[str]]:
    """Run ``isolator ARGV`` in this process: its exit status, stdout and stderr lines."""
    from isolator.cli.app import main

    try:
        status = main(argv)
    except SystemExit as exc:
        status = int(exc.code or 0)
    captured = capsys.readouterr()
    return status, captured.out, captured.err.splitlines()
