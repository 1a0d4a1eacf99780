"""Calibration round trips on records the MuJoCo check made of a table with known "true" isolators."""

from __future__ import annotations

import json

import numpy as np
import pytest

from isolator import load_scenario
from isolator.calibration import calibrate
from isolator.cli.app import main


@pytest.mark.parametrize("experiments", [("floor",), ("move",), ("floor", "move")])
def test_parameters_recovered_within_their_intervals(tmp_path, mujoco_records, write_calibration, true_values,
                                                     experiments):
    move, floor = mujoco_records
    result = calibrate(write_calibration(tmp_path, move, floor, seed=3, experiments=experiments))
    assert result.identifiable
    for name, true in true_values.items():
        e = result.parameters[name]
        # within 4 standard deviations; a floor-only fit on a 60 s record carries H1's leakage bias (~1 %), which
        # its intervals do not yet cover (known, see the notes)
        if "move" in experiments:
            assert abs(e.value - true) < 4 * e.std, (name, true, e)
        assert abs(e.value / true - 1) < 0.02
        assert abs(e.initial / true - 1) > 0.1  # the datasheet values were 15-30 % off
    for fit in result.experiments.values():  # the fitted model explains each record to its noise
        assert fit["residual_after"] < (3.0 if fit["kind"] == "floor" else 1.2)  # H1's leakage bias on 60 s
        assert fit["residual_before"] > 2 * fit["residual_after"]


def test_fitted_scenario_loads_and_carries_the_values(tmp_path, mujoco_records, write_calibration):
    move, floor = mujoco_records
    path = write_calibration(tmp_path, move, floor, seed=5, experiments=("move",))
    out = tmp_path / "out" / "fitted.toml"
    assert main(["calibrate", str(path), "--out", str(out), "--json"]) == 0
    fitted = load_scenario(out)
    result = calibrate(path)
    for k, iso in enumerate(fitted.isolators):
        assert np.allclose(iso.stiffness, [result.parameters[f"isolators[*].stiffness.{a}"].value for a in "xyz"],
                           rtol=1e-9), k
    assert fitted.carriages == load_scenario(tmp_path / "table.toml").carriages


def test_json_has_the_contract_keys(tmp_path, mujoco_records, write_calibration, true_values, capsys):
    move, floor = mujoco_records
    path = write_calibration(tmp_path, move, floor, seed=7, experiments=("floor",))
    assert main(["calibrate", str(path), "--out", str(tmp_path / "f.toml"), "--json", "--plot",
                 str(tmp_path / "fit.png"), "--report", str(tmp_path / "rep")]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data) >= {"parameters", "identifiable", "unidentifiable", "correlation", "experiments", "modes"}
    assert list(data["parameters"]) == list(true_values)
    assert set(data["parameters"]["isolators[*].stiffness.x"]) == {"initial", "value", "std", "ci95"}
    assert np.asarray(data["correlation"]).shape == (6, 6)
    assert data["experiments"]["floor"]["kind"] == "floor"
    assert len(data["modes"]["fitted"]["frequencies_hz"]) == 6
    assert (tmp_path / "fit.png").stat().st_size > 10_000
    assert "| parameter |" in (tmp_path / "rep" / "report.md").read_text()
