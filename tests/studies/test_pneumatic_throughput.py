"""The pneumatic study's runs through isolator.sweep: with ``[[windows]]`` each design's window settling and
moves per hour, as the single run of the design gives them."""

from __future__ import annotations

import csv
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from isolator import Simulator, load_scenario
from isolator.simulation.window_settling import moves_per_hour
from studies.pneumatic import default_diameters, run_pneumatic_study

DATA = Path(__file__).resolve().parents[2] / "isolator" / "data" / "scenarios"
# +-50 um: the window is about the final level rest, and the valves' deadband is 20 um (a narrower window
# than the leveling's deadband never holds)
WINDOW = ('\n[[points]]\nname = "probe"\nposition = [0.0, 0.0, 0.5]\n\n'
          '[[windows]]\npoint = "probe"\ntranslation = 5e-5\n')


def test_with_a_window_each_design_gets_window_settling_and_moves_per_hour(tmp_path):
    path = tmp_path / "pneumatic-window.toml"
    path.write_text((DATA / "paper-table-3-2-pneumatic.toml").read_text() + WINDOW)
    sc = load_scenario(path)
    d = default_diameters(sc)[[4, 10]]
    study = run_pneumatic_study(tmp_path / "out", sc, diameters=d, ratios=[1.0, 4.0], progress=False, workers=1)
    runs = study.runs
    assert np.isfinite(runs.per_hour).all()
    for i, j in ((0, 0), (1, 1)):
        sim = Simulator(replace(sc, simulation=replace(sc.simulation, duration=float(runs.duration[i, j]))))
        changes = {}
        for k, iso in enumerate(sc.isolators):
            changes[f"isolators[{k}].orifice.diameter"] = d[i]
            changes[f"isolators[{k}].damping_volume"] = study.ratios[j] * iso.volume
        run = sim.run(p=sim.parameter_vector(changes))
        assert runs.window[i, j] == pytest.approx(run.window_settling_time_max, abs=1e-12)
        expected = moves_per_hour(run.stop_time - run.move_start, run.window_settling_time_max)
        assert runs.per_hour[i, j] == pytest.approx(expected, rel=1e-12)
        assert runs.settling[i, j] == pytest.approx(run.pneumatic.dynamic_settling_time_max, abs=1e-12)
    assert np.isfinite(study.own_runs.per_hour[0, 0])
    with open(study.folder / "designs.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert float(rows[3]["moves_per_hour"]) == pytest.approx(runs.per_hour[1, 1], rel=1e-5)
    report = (study.folder / "report.md").read_text()
    assert "| window settling [s] | moves per hour |" in report
    assert "Most moves per hour on the grid" in report
