"""What each design buys in throughput: window settling and moves per hour in the studies."""

from __future__ import annotations

import json
import tomllib

import pytest
import tomli_w

from isolator import Simulator, load_scenario
from isolator.cli.app import main
from isolator.scenario.reader import resolve_scenario_path
from isolator.simulation.window_settling import moves_per_hour
from studies.throughput import window_cycle


def _with_window(source: str, path, half_width: float):
    with open(resolve_scenario_path(source), "rb") as handle:
        data = tomllib.load(handle)
    data["points"] = [{"name": "probe", "position": [0.0, 0.0, 0.5]}]
    data["windows"] = [{"point": "probe", "translation": half_width}]
    with open(path, "wb") as handle:
        tomli_w.dump(data, handle)
    return path


def test_moves_per_hour_by_hand():
    assert moves_per_hour(7.0, 2.0) == pytest.approx(400.0)
    assert moves_per_hour(None, 2.0) is None
    assert moves_per_hour(7.0, None) is None
    assert moves_per_hour(0.0, 0.0) is None


def test_window_cycle_of_a_run(tmp_path):
    sc = load_scenario(_with_window("paper-table-3-2", tmp_path / "w.toml", 5e-7))
    response = Simulator(sc).run()
    settle, rate = window_cycle(response)
    assert settle == response.window_settling_time_max
    assert rate == pytest.approx(3600.0 / (response.stop_time - response.move_start + settle))
    assert window_cycle(Simulator(load_scenario("paper-table-3-2")).run()) == (None, None)


@pytest.mark.slow
def test_control_study_reports_window_settling_and_moves_per_hour(tmp_path, capsys):
    path = _with_window("paper-table-3-2-active", tmp_path / "active.toml", 5e-7)
    assert main(["study", "control", str(path), "--out", str(tmp_path / "out")]) == 0
    assert "moves per hour" in capsys.readouterr().out
    data = json.loads((tmp_path / "out" / "results.json").read_text())
    passive = Simulator(load_scenario(path)).run()
    assert data["passive"]["window_settling_time_max"] == pytest.approx(passive.window_settling_time_max, abs=1e-9)
    # cancelling the reaction forces buys moves: the feedforward run settles inside the window sooner
    assert data["feedforward"]["moves_per_hour"] > data["passive"]["moves_per_hour"]
    assert "## At the windows" in (tmp_path / "out" / "report.md").read_text()
