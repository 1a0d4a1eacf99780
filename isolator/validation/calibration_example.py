"""The bundled calibration example: the paper's Table 3.2 table with its datasheet isolators, and SYNTHETIC
records of the "true" table (isolators 15-30 % off the datasheet) made by the independent MuJoCo check
(:mod:`isolator.validation.synthetic_records`) with 1 % sensor noise.

``python -m isolator.validation.calibration_example DIR`` writes it again (``table.toml``, ``true.toml``,
``calibration.toml``, ``floor.csv``, ``move.csv``, ``README.md``; ``--noise-free FILE.npz`` also the
records without noise, which the coverage test adds its own noise to).
"""

from __future__ import annotations

import argparse
import copy
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from isolator.scenario.output_files import write_output_text
from isolator.scenario.reader import resolve_scenario_path, scenario_from_dict
from isolator.scenario.writing import write_toml
from isolator.validation.synthetic_records import FloorMotion, SyntheticRecord, floor_record, move_record

__all__ = ["FIT", "TRUE_FACTORS", "calibration_text", "make_example", "records", "table_data", "true_data",
           "true_values"]

#: the "true" isolators as factors on the datasheet's (stiffness x, y, z; damping x, y, z)
TRUE_FACTORS = (1.2, 0.85, 1.15, 0.75, 1.3, 0.8)
#: what the example fits: every isolator's stiffness and damping per axis, one value shared by the four
FIT = ("isolators[*].stiffness.x", "isolators[*].stiffness.y", "isolators[*].stiffness.z",
       "isolators[*].damping.x", "isolators[*].damping.y", "isolators[*].damping.z")
#: the records: the floor's (duration [s], rate [Hz], band [Hz]) and the move's (duration [s], rate [Hz])
FLOOR = (60.0, 200.0, (0.5, 25.0))
MOVE = (9.0, 500.0)
NOISE = 0.01


def table_data() -> dict[str, Any]:
    """The paper's Table 3.2 (datasheet isolators) with nine table accelerometers (x, y, z at three top
    corners) and three floor accelerometers."""
    data = tomllib.loads(resolve_scenario_path("paper-table-3-2").read_text())
    data["name"] = "calibration-table"
    sensors = []
    for i, (x, y) in enumerate([(0.95, 0.45), (-0.95, 0.45), (-0.95, -0.45)]):
        for axis, d in (("x", [1.0, 0.0, 0.0]), ("y", [0.0, 1.0, 0.0]), ("z", [0.0, 0.0, 1.0])):
            sensors.append({"name": f"a{i}-{axis}", "on": "table", "position": [x, y, 0.15], "direction": d,
                            "quantity": "acceleration"})
    for axis, d in (("x", [1.0, 0.0, 0.0]), ("y", [0.0, 1.0, 0.0]), ("z", [0.0, 0.0, 1.0])):
        sensors.append({"name": f"f-{axis}", "on": "floor", "position": [0.0, 0.0, -0.5], "direction": d,
                        "quantity": "acceleration"})
    data["sensors"] = sensors
    return data


def true_data() -> dict[str, Any]:
    """The same table with the "true" isolators (:data:`TRUE_FACTORS` on the datasheet's)."""
    data = copy.deepcopy(table_data())
    data["name"] = "calibration-table-true"
    for iso in data["isolators"]:
        iso["stiffness"] = [k * f for k, f in zip(iso["stiffness"], TRUE_FACTORS[:3], strict=True)]
        iso["damping"] = [c * f for c, f in zip(iso["damping"], TRUE_FACTORS[3:], strict=True)]
    return data


def true_values() -> dict[str, float]:
    """The fitted names' true values [SI]."""
    iso = true_data()["isolators"][0]
    return dict(zip(FIT, [*iso["stiffness"], *iso["damping"]], strict=True))


def records(floor: tuple[float, float, tuple[float, float]] = FLOOR, move: tuple[float, float] = MOVE
            ) -> tuple[SyntheticRecord, SyntheticRecord]:
    """Noise-free MuJoCo records of the true table: the move, and the floor (a band-limited random floor
    along x, y, z)."""
    true = scenario_from_dict(true_data())
    duration, rate, (low, high) = floor
    return (move_record(true, move[0], move[1]),
            floor_record(true, FloorMotion(low=low, high=high), duration, rate))


def calibration_text(experiments: tuple[str, ...] = ("floor", "move")) -> str:
    """The calibration file (TOML) of the example."""
    lines = ["# SYNTHETIC records: made by isolator's independent MuJoCo check of the table in true.toml",
             "# (isolators 15-30 % off the datasheet values in table.toml), 1 % sensor noise.",
             'scenario = "table.toml"', f"fit = {list(FIT)!r}".replace("'", '"'), ""]
    if "floor" in experiments:
        low, high = FLOOR[2]
        lines += ["[[experiments]]", 'name = "floor-random"', 'file = "floor.csv"', 'kind = "floor"',
                  f"frequency = [{max(low, 1.0)}, {min(high, 20.0)}]", ""]
    if "move" in experiments:
        lines += ["[[experiments]]", 'name = "move"', 'file = "move.csv"', 'kind = "move"', ""]
    return "\n".join(lines)


def make_example(folder: str | Path, noise_free: tuple[SyntheticRecord, SyntheticRecord] | None = None,
                 seed: int = 2026, experiments: tuple[str, ...] = ("floor", "move")) -> Path:
    """Write the example into ``folder`` (records with :data:`NOISE` of each channel's RMS, ``seed``);
    returns the calibration file."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    move, floor = noise_free if noise_free is not None else records()
    write_toml(table_data(), folder / "table.toml")
    write_toml(true_data(), folder / "true.toml")
    if "floor" in experiments:
        floor.noisy(NOISE, seed).write_csv(folder / "floor.csv")
    if "move" in experiments:
        move.noisy(NOISE, seed + 1).write_csv(folder / "move.csv")
    write_output_text(folder / "README.md",
        "# Calibration example (SYNTHETIC records)\n\nThe records here were made by isolator's independent MuJoCo "
        "check of `true.toml` (the paper's Table 3.2 table with isolators 15-30 % off the datasheet values of "
        f"`table.toml`), read by the sensors of `table.toml` with {NOISE:.0%} white noise of each channel's RMS. "
        "They are not measurements. `isolator calibrate calibration.toml --out fitted.toml` should recover the "
        "isolators of `true.toml` within its intervals.\n")
    path = folder / "calibration.toml"
    write_output_text(path, calibration_text(experiments))
    return path


def _main() -> None:
    parser = argparse.ArgumentParser(description="write the calibration example (SYNTHETIC MuJoCo records)")
    parser.add_argument("folder", type=Path)
    parser.add_argument("--noise-free", type=Path, metavar="FILE.npz", help="also save the records without noise")
    args = parser.parse_args()
    move, floor = records()
    if args.noise_free is not None:
        arrays: dict[str, Any] = {"move_t": move.t, "floor_t": floor.t,
                                  **{f"move:{k}": v for k, v in move.channels.items()},
                                  **{f"floor:{k}": v for k, v in floor.channels.items()}}
        np.savez_compressed(args.noise_free, **arrays)
    print(make_example(args.folder, (move, floor)))


if __name__ == "__main__":
    _main()
