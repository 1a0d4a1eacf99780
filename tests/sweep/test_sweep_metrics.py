"""The columns a sweep adds beyond the batch: each design's band (every scenario), the pneumatic figures,
window settling and moves per hour, a sequence's total time and throughput; each as the single run of the
design gives it, serial and pool alike."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from conftest import same_columns
from isolator import Simulator, load_scenario, run_sequence
from isolator.scenario.definitions import SIGNALS
from isolator.simulation.window_settling import moves_per_hour
from isolator.sweep import sweep
from isolator.sweep.metrics import PNEUMATIC_COLUMNS, SEQUENCE_COLUMNS, WINDOW_COLUMNS
from isolator.sweep.output import read_columns

DATA = Path(__file__).resolve().parents[2] / "isolator" / "data" / "scenarios"
WINDOW = ('\n[[points]]\nname = "probe"\nposition = [0.0, 0.0, 0.5]\n\n'
          '[[windows]]\npoint = "probe"\ntranslation = 5e-7\n')


def window_scenario(folder: Path) -> Path:
    """Table 3.2 with a probe 0.5 m above the mass centre and a +-0.5 um window at it."""
    path = folder / "table-3-2-window.toml"
    path.write_text((DATA / "paper-table-3-2.toml").read_text() + WINDOW)
    return path


def test_the_band_columns_are_each_designs_band():
    scale = {"isolators[*].stiffness": [0.8, 1.7], "isolators[*].damping": [1.5, 2.0]}
    result = sweep("paper-table-3-2", scale=scale, zip=True, workers=1)
    assert result.columns[-6:] == tuple(f"band:{s}" for s in SIGNALS)
    sim = Simulator(load_scenario("paper-table-3-2"))
    for r, (k, c) in enumerate(zip(*scale.values(), strict=True)):
        run = sim.run(p=sim.scaled_parameters(k, c))
        widths = [result[f"band:{s}"][r] for s in SIGNALS]
        np.testing.assert_allclose(widths, run.band.half_widths, rtol=1e-9)
        assert result["settling_time_max"][r] == pytest.approx(run.settling_time_max, abs=1e-9)


def test_pneumatic_rows_carry_the_settling_about_the_leveling_table_and_the_leveling():
    scale = {"isolators[*].orifice.diameter": [0.8, 1.0, 1.3]}
    serial = sweep("paper-table-3-2-pneumatic", scale=scale, workers=1)
    assert serial.columns[-3:] == PNEUMATIC_COLUMNS
    sim = Simulator(load_scenario("paper-table-3-2-pneumatic"))
    for r, f in enumerate(scale["isolators[*].orifice.diameter"]):
        p = sim.parameters.copy()
        at = [i for i, n in enumerate(sim.layout.names) if n.endswith(".orifice.diameter")]
        p[at] *= f
        run = sim.run(p=p)
        pneumatic = run.pneumatic
        assert serial["status"][r] == "ok"
        assert serial["settling_time_max"][r] == pytest.approx(run.settling_time_max, abs=1e-12)
        assert serial["dynamic_settling_time_max"][r] == pytest.approx(pneumatic.dynamic_settling_time_max, abs=1e-12)
        assert serial["leveling_time"][r] == pytest.approx(max(pneumatic.leveling_time.values()), abs=1e-12)
        assert serial["supply_exhausted"][r] == float(bool(pneumatic.supply_exhausted))
        np.testing.assert_allclose([serial[f"band:{s}"][r] for s in SIGNALS], run.band.half_widths, rtol=1e-12)
    same_columns(serial.table(), sweep("paper-table-3-2-pneumatic", scale=scale, workers=2, chunk_size=1).table())


def test_window_rows_carry_window_settling_and_moves_per_hour(tmp_path):
    path = window_scenario(tmp_path)
    scale = {"isolators[*].damping": [1.0, 2.0, 3.0]}
    out = tmp_path / "rows.csv"
    result = sweep(path, scale=scale, workers=2, chunk_size=1, out=out)
    assert result.columns[-2:] == WINDOW_COLUMNS
    sc = load_scenario(path)
    sim = Simulator(sc)
    for r, c in enumerate(scale["isolators[*].damping"]):
        run = sim.run(p=sim.scaled_parameters(1.0, c))
        assert result["status"][r] == "ok"
        assert result["window_settling_time_max"][r] == pytest.approx(run.window_settling_time_max, abs=1e-12)
        expected = moves_per_hour(run.stop_time - run.move_start, run.window_settling_time_max)
        assert result["moves_per_hour"][r] == pytest.approx(expected, rel=1e-12)
        assert result["settling_time_max"][r] == pytest.approx(run.settling_time_max, abs=1e-12)
    assert np.all(np.diff(result["window_settling_time_max"]) < 0)  # damping shortens the window settling
    same_columns(read_columns(out), sweep(path, scale=scale, workers=1).table())


def test_sequence_rows_carry_total_time_throughput_and_the_step_that_did_not_settle():
    sc = load_scenario("paper-table-3-2-sequence")
    scale = {"isolators[*].damping": [0.5, 2.0]}
    result = sweep(sc, scale=scale, workers=1)
    assert result.columns[-3:] == SEQUENCE_COLUMNS
    assert np.isnan(result["settling_time_max"]).all()
    assert np.isnan(result["band:x"]).all()
    sim = Simulator(sc)
    for r, c in enumerate(scale["isolators[*].damping"]):
        one = run_sequence(sc, parameters=sim.scaled_parameters(1.0, c))
        assert result["status"][r] == "ok"
        assert result["total_time"][r] == pytest.approx(one.total_time, abs=1e-12)
        assert result["throughput_per_hour"][r] == pytest.approx(one.throughput, rel=1e-12)
        assert np.isnan(result["unsettled_step"][r])
    assert result["throughput_per_hour"][1] > result["throughput_per_hour"][0]
    same_columns(result.table(), sweep(sc, scale=scale, workers=2, chunk_size=1).table())
    short = sc.with_changes(simulation=replace(sc.simulation, duration=30.0))
    cut = sweep(short, scale={"isolators[*].damping": [0.5]}, workers=1)
    step = run_sequence(short, parameters=sim.scaled_parameters(1.0, 0.5)).unsettled
    assert step is not None
    assert cut["status"][0] == "unsettled"
    assert cut["unsettled_step"][0] == step
    assert f"step {step} did not settle" in cut["reason"][0]
    assert np.isnan(cut["total_time"][0])


def test_a_sequence_sweep_is_judged_by_its_total_time_and_resumes(tmp_path):
    scale = {"isolators[*].damping": [0.5, 1.0, 2.0]}
    out = tmp_path / "rows.csv"
    first = sweep("paper-table-3-2-sequence", scale=scale, workers=1, out=out)
    rows = first.table()
    best = first.best()
    assert best is not None
    assert best["isolators[*].damping"] == 2.0
    assert best["total_time"] == pytest.approx(first["total_time"][2], rel=1e-12)
    assert "total_time = " in first.summary()
    lines = out.read_text().splitlines(keepends=True)
    out.write_text("".join(lines[:2]))  # interrupted after the first design
    again = sweep("paper-table-3-2-sequence", scale=scale, workers=1, out=out, resume=True)
    assert again.tally.resumed == 1
    assert again.best() == best
    same_columns(again.table(), rows)
