"""Speed of a calibration (issue 23's targets), each against the same fit with finite-difference Jacobians
measured in the same run.

- Floor: 120 s at 500 Hz, 9 table + 3 floor accelerometers (12 channels), 6 parameters (stiffness and damping
  per axis of the example table); the records are the linear model's steady response to a random floor
  (periodic, computed exactly in the frequency domain) with 1 % noise. Target: at most 10 s. Baseline: the
  fit with scipy's forward differences of the residuals (``jacobian="differences"``).
- Move: 7 s at 1 kHz, the 9 table accelerometers, 6 parameters; the records are the time-varying model's own
  run of the true table (a shorter move than the paper's, which stops after 7 s) with 1 % noise. Target: at
  most 30 s. Baseline: forward differences with each perturbed run on its own.

Both fits start at the datasheet values (15-30 % off). Speed only: the round trips on records of the
independent MuJoCo check are the tests'.
Run:  python benchmarks/bench_calibration.py [--skip-baseline]
"""

from __future__ import annotations

import argparse
import copy
import tempfile
import time
from pathlib import Path

import numpy as np
import tomli_w

from isolator import ParameterLayout, scenario_from_dict, simulate
from isolator.calibration import calibrate
from isolator.calibration.floor_model import FloorModel
from isolator.validation.calibration_example import FIT, table_data, true_data, true_values


def _move_table(data: dict) -> dict:
    data = copy.deepcopy(data)
    data["carriages"][0]["profile"] = {"type": "trapezoid", "start": -0.3, "stroke": 0.6, "velocity": 0.2,
                                       "acceleration": 0.5, "t0": 0.2}
    data["carriages"][1]["profile"] = {"type": "trapezoid", "start": -0.15, "stroke": 0.3, "velocity": 0.1,
                                       "acceleration": 0.5, "t0": 0.2}
    data["simulation"] = {"duration": 7.0, "sample_rate": 1000.0}
    return data


def _write_csv(path: Path, t: np.ndarray, channels: dict[str, np.ndarray], seed: int) -> None:
    rng = np.random.default_rng(seed)
    noisy = [v + 0.01 * np.sqrt(np.mean(v**2)) * rng.standard_normal(v.size) for v in channels.values()]
    np.savetxt(path, np.column_stack([t, *noisy]), delimiter=",", header=",".join(["t", *channels]), comments="",
               fmt="%.10g")


def floor_case(folder: Path, duration: float = 120.0, rate: float = 500.0) -> Path:
    """The floor calibration's files; returns the calibration file."""
    true = scenario_from_dict(true_data())
    layout = ParameterLayout.of(true)
    table = tuple(s for s in true.sensors if s.on == "table")
    n = int(duration * rate)
    f = np.fft.rfftfreq(n, 1 / rate)
    rng = np.random.default_rng(1)
    spectrum = np.zeros((3, f.size), complex)
    band = (f >= 0.5) & (f <= 40.0)
    spectrum[:, band] = np.exp(2j * np.pi * rng.uniform(size=(3, int(band.sum()))))
    acc = np.fft.irfft(spectrum, n, axis=1)
    h = np.zeros((len(table), 3, f.size), complex)
    h[:, :, 1:] = FloorModel(layout, true.initial_positions(), table).response(layout.pack(true), f[1:]).H
    disp = np.zeros_like(spectrum)
    disp[:, 1:] = spectrum[:, 1:] / -(2 * np.pi * f[1:]) ** 2
    y = np.fft.irfft(np.einsum("skf,kf->sf", h, disp), n, axis=1)
    channels = {s.name: y[i] for i, s in enumerate(table)}
    channels.update({f"f-{a}": acc[k] for k, a in enumerate("xyz")})
    _write_csv(folder / "floor.csv", np.arange(n) / rate, channels, 2)
    (folder / "table.toml").write_bytes(tomli_w.dumps(table_data()).encode())
    path = folder / "floor.toml"
    path.write_text(f'scenario = "table.toml"\nfit = {list(FIT)!r}\n'.replace("'", '"')
                    + '[[experiments]]\nname = "floor"\nfile = "floor.csv"\nkind = "floor"\nfrequency = [1.0, 30.0]\n')
    return path


def move_case(folder: Path) -> Path:
    """The move calibration's files; returns the calibration file."""
    run = simulate(scenario_from_dict(_move_table(true_data())))
    channels = {n: run.sensor(n) for n in run.sensor_names if not n.startswith("f-")}
    _write_csv(folder / "move.csv", run.t, channels, 3)
    (folder / "move-table.toml").write_bytes(tomli_w.dumps(_move_table(table_data())).encode())
    path = folder / "move.toml"
    path.write_text(f'scenario = "move-table.toml"\nfit = {list(FIT)!r}\n'.replace("'", '"')
                    + '[[experiments]]\nname = "move"\nfile = "move.csv"\nkind = "move"\n')
    return path


def _fit(path: Path, jacobian: str) -> tuple[float, float, int]:
    """Wall time [s], the largest error against the true values [%], model evaluations."""
    t0 = time.perf_counter()
    result = calibrate(path, jacobian=jacobian)
    wall = time.perf_counter() - t0
    truth = true_values()
    worst = max(abs(e.value / truth[n] - 1) for n, e in result.parameters.items()) * 100
    return wall, worst, result.fit.evaluations


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--skip-baseline", action="store_true", help="time the toolkit's fits only")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        cases = [("floor 120 s at 500 Hz, 12 channels, 6 parameters", floor_case(folder), 10.0),
                 ("move 7 s at 1 kHz, 9 channels, 6 parameters", move_case(folder), 30.0)]
        calibrate(cases[1][1])  # compile the model and the stepper before timing
        for label, path, target in cases:
            wall, worst, count = _fit(path, "model")
            line = f"{label}: {wall:6.2f} s ({count} evaluations, worst parameter error {worst:.3f} %; target <= " \
                   f"{target:g} s)"
            if not args.skip_baseline:
                base, base_worst, base_count = _fit(path, "differences")
                line += (f"\n    finite differences: {base:6.2f} s ({base_count} evaluations, worst "
                         f"{base_worst:.3f} %)  -> x{base / wall:.1f} faster")
            print(line, flush=True)


if __name__ == "__main__":
    main()
