"""The isolator command, as a user runs it."""

from __future__ import annotations

import csv
import json
import subprocess
import sys

import pytest

from isolator.cli.app import main


def test_simulate_default_prints_table_and_writes_figure(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate"]) == 0
    out = capsys.readouterr().out
    assert "paper-table-3-2 (exact model)" in out
    for name in ("x", "y", "z", "rx", "ry", "rz"):
        assert f"\n{name:>6}  " in out
    assert "settling time (largest):" in out
    assert (tmp_path / "paper-table-3-2.png").stat().st_size > 10_000


def test_simulate_json_and_csv(tmp_path, capsys):
    csv_path = tmp_path / "r.csv"
    assert main(["simulate", "paper-table-3-2", "--model", "paper", "--json", "--out", str(csv_path)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data) >= {"name", "model", "stop_time", "signals", "peak", "final", "settling_time",
                         "settling_time_max"}
    assert data["model"] == "paper"
    assert data["signals"] == ["x", "y", "z", "rx", "ry", "rz"]
    assert data["stop_time"] == pytest.approx(7.9, abs=1e-3)
    assert data["settling_time_max"] == pytest.approx(max(data["settling_time"].values()))
    with open(csv_path) as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == ["t", "x", "y", "z", "rx", "ry", "rz", "q:x-stage", "q:y-stage"]
    assert len(rows) == 12001 + 1
    assert float(rows[-1][7]) == pytest.approx(0.7)


def test_sine_scenario_has_no_settling_time(capsys):
    assert main(["simulate", "paper-table-3-1", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["stop_time"] is None
    assert data["settling_time_max"] is None
    assert "never stops" in data["notes"]["x"]


def test_errors_are_one_line_without_traceback(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[table]\nmass = 10\nsize = [1, 1, 0.1]\n[[isolators]]\nposition = [0, 0, 0]\n'
                   'stiffness = [1, 1, 1]\ndamping = [0, 0, 0]\n')
    proc = subprocess.run([sys.executable, "-m", "isolator.cli", "simulate", str(bad)],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stderr.strip() == "isolator: error: isolators: need at least three, got 1"
    assert "Traceback" not in proc.stderr
