"""Synthetic records of a table whose isolators are 10-30 % off the scenario's, made by the independent
MuJoCo check (not the model being fitted), with 1 % sensor noise."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import pytest
import tomli_w

from isolator.scenario.reader import resolve_scenario_path

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
