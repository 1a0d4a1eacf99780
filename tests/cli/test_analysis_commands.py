"""The linear-analysis commands: modes, transmissibility, stability, criteria."""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path

import pytest

from isolator.analysis.vibration import third_octave_bands
from isolator.cli.app import main


def test_modes_command_json(capsys):
    assert main(["modes", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data) >= {"frequencies_hz", "damping_ratios", "shapes", "dominant"}
    assert len(data["frequencies_hz"]) == 6
    assert data["frequencies_hz"] == sorted(data["frequencies_hz"])
    assert set(data["shapes"][0]) == {"x", "y", "z", "rx", "ry", "rz"}
    assert set(data["dominant"]) <= {"x", "y", "z", "rx", "ry", "rz"}


def test_transmissibility_command_json_and_plot(tmp_path: Path, capsys):
    plot = tmp_path / "t.png"
    assert main(["transmissibility", "--json", "--plot", str(plot), "--points", "200"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert len(data["frequency_hz"]) == 200
    assert set(data["magnitude"]) == {"x", "y", "z", "rx", "ry", "rz"}
    assert all(len(v) == 200 for v in data["magnitude"].values())
    assert data["magnitude"]["z"][0] == pytest.approx(1.0, abs=2e-3)  # follows the floor at 0.1 Hz
    assert all(v is None or v > 0 for v in data["isolation_above_hz"].values())
    assert plot.stat().st_size > 10_000


def test_stability_command_reports_margin_and_exit_status(tmp_path: Path, capsys):
    assert main(["stability"]) == 0
    assert "stable; smallest rocking stiffness" in capsys.readouterr().out
    text = resources.files("isolator").joinpath("data", "scenarios", "paper-table-3-2.toml")
    tipping = text.read_text().replace("[5.7e5, 5.7e5, 5.7e5]", "[5.7e3, 5.7e3, 5.7e3]")  # too soft to hold it
    path = tmp_path / "tall.toml"
    path.write_text(tipping)
    assert main(["stability", str(path), "--json"]) == 3
    report = json.loads(capsys.readouterr().out)
    assert report["stable"] is False
    assert report["margin"] < 0
    assert main(["simulate", str(path), "--json"]) == 2
    assert "rocking stiffness" in capsys.readouterr().err


def test_criteria_command(tmp_path: Path, capsys):
    path = tmp_path / "floor.csv"
    centres, _, _ = third_octave_bands(1.0, 80.0)
    path.write_text("frequency_hz,x,y,z\n" + "".join(f"{float(f)!r},3e-6,3e-6,6e-6\n" for f in centres))
    plot = tmp_path / "vc.png"
    assert main(["criteria", "--spectrum", str(path), "--plot", str(plot)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("floor: VC-D; table at mass centre:")  # 6 um/s <= 6.25
    assert plot.stat().st_size > 10_000
    assert main(["criteria"]) == 2
    assert "ground.spectrum: no floor spectrum" in capsys.readouterr().err
