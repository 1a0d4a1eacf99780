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
import tomllib
from pathlib import Path
from typing import Any

import pytest
import tomli_w
from hypothesis import HealthCheck, settings

from isolator import Scenario, scenario_from_dict
from isolator.scenario.reader import resolve_scenario_path

# property-based tests (tests/properties): few examples in CI, many with HYPOTHESIS_PROFILE=thorough
settings.register_profile("ci", max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("thorough", max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))
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


# -- calibration: synthetic records of a table whose isolators are 10-30 % off (the MuJoCo check) --
#: the "true" isolators as factors on the scenario's (stiffness x, y, z; damping x, y, z)
TRUE_FACTORS = (1.2, 0.85, 1.15, 0.75, 1.3, 0.8)
FIT = ["isolators[*].stiffness.x", "isolators[*].stiffness.y", "isolators[*].stiffness.z",
       "isolators[*].damping.x", "isolators[*].damping.y", "isolators[*].damping.z"]


def table_data() -> dict:
    """The paper's Table 3.2 with nine table accelerometers (three corners, x y z) and three floor ones."""
    data = tomllib.loads(resolve_scenario_path("paper-table-3-2").read_text())
    data["name"] = "calibration-table"
    sensors = []
    for i, (x, y) in enumerate([(0.95, 0.45), (-0.95, 0.45), (-0.95, -0.45)]):
        for axis, d in (("x", [1.0, 0, 0]), ("y", [0, 1.0, 0]), ("z", [0, 0, 1.0])):
            sensors.append({"name": f"a{i}-{axis}", "on": "table", "position": [x, y, 0.15], "direction": d,
                            "quantity": "acceleration"})
    for axis, d in (("x", [1.0, 0, 0]), ("y", [0, 1.0, 0]), ("z", [0, 0, 1.0])):
        sensors.append({"name": f"f-{axis}", "on": "floor", "position": [0, 0, -0.5], "direction": d,
                        "quantity": "acceleration"})
    data["sensors"] = sensors
    return data


def true_data() -> dict:
    data = copy.deepcopy(table_data())
    k, c = data["isolators"][0]["stiffness"][0], data["isolators"][0]["damping"][0]
    for iso in data["isolators"]:
        iso["stiffness"] = [k * f for f in TRUE_FACTORS[:3]]
        iso["damping"] = [c * f for f in TRUE_FACTORS[3:]]
    return data


@pytest.fixture(scope="session")
def mujoco_records():
    """Noise-free MuJoCo records of the true table: a move (9 s at 500 Hz) and a floor record (60 s at 200 Hz)."""
    pytest.importorskip("mujoco")
    from isolator import scenario_from_dict
    from isolator.validation.synthetic_records import FloorMotion, floor_record, move_record

    true = scenario_from_dict(true_data())
    move = move_record(true, 9.0, 500.0)
    floor = floor_record(true, FloorMotion(low=0.5, high=25.0, count=120), 60.0, 200.0)
    return move, floor


@pytest.fixture(scope="session")
def true_values() -> dict:
    """The true table's fitted values by name [SI]."""
    k, c = 5.7e5, 5.7e3
    return dict(zip(FIT, [k * f for f in TRUE_FACTORS[:3]] + [c * f for f in TRUE_FACTORS[3:]], strict=True))


@pytest.fixture(scope="session")
def write_calibration():
    """``write(folder, move, floor, seed, experiments)``: the files of a calibration (see :func:`_write`)."""
    return _write


def _write(folder: Path, move, floor, seed: int, experiments=("floor", "move")) -> Path:
    """The scenario, noisy records (1 % of each channel's RMS) and a calibration file fitting FIT."""
    (folder / "table.toml").write_bytes(tomli_w.dumps(table_data()).encode())
    blocks = []
    if "floor" in experiments:
        floor.noisy(0.01, seed).write_csv(folder / "floor.csv")
        blocks.append('[[experiments]]\nname = "floor"\nfile = "floor.csv"\nkind = "floor"\nfrequency = [1.0, 20.0]\n')
    if "move" in experiments:
        move.noisy(0.01, seed + 1000).write_csv(folder / "move.csv")
        blocks.append('[[experiments]]\nname = "move"\nfile = "move.csv"\nkind = "move"\n')
    path = folder / "calibration.toml"
    path.write_text(f'scenario = "table.toml"\nfit = {FIT!r}\n\n' + "\n".join(blocks))
    return path
