"""The trade-off study on isolator.sweep: the same numbers as the batch it replaced, each design's window
settling and moves per hour with ``[[windows]]``, and a ``[sequence]``'s total time and steps per hour."""

from __future__ import annotations

import csv
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from isolator import Simulator, load_scenario, run_sequence
from isolator.scenario.definitions import SIGNALS
from isolator.simulation.scaling import scale_columns
from isolator.simulation.window_settling import moves_per_hour
from isolator.sweep import build_designs
from studies.tradeoff import run_tradeoff_study, tradeoff_sweep

DATA = Path(__file__).resolve().parents[2] / "isolator" / "data" / "scenarios"
WINDOW = ('\n[[points]]\nname = "probe"\nposition = [0.0, 0.0, 0.5]\n\n'
          '[[windows]]\npoint = "probe"\ntranslation = 5e-7\n')
K, C = [0.5, 1.0, 2.0], [0.5, 1.0, 2.0, 4.0]


def test_the_sweep_gives_the_batch_it_replaced():
    sc = load_scenario("paper-table-3-2")
    sim = Simulator(sc)
    kk, cc = (v.ravel() for v in np.meshgrid([0.7, 1.0, 1.6], [1.0, 2.5], indexing="ij"))
    rows = tradeoff_sweep(sc, kk, cc, workers=1).table()
    batch = sim.run_batch(kk, cc, workers=1, diverged="record")
    np.testing.assert_allclose(rows["settling_time_max"], batch.settling_time_max, rtol=0, atol=1e-9)
    widths = np.column_stack([rows[f"band:{s}"] for s in SIGNALS])
    np.testing.assert_allclose(widths, batch.half_widths, rtol=1e-12)


@pytest.mark.parametrize("name", ["paper-table-3-2-pneumatic", "paper-table-3-2"])
def test_the_scale_columns_are_the_scaled_parameter_sets(name):
    sim = Simulator(load_scenario(name))
    k, c = np.array([0.7, 1.0, 1.3]), np.array([0.5, 1.0, 2.0])
    designs = build_designs(sim.layout, sim.parameters, None, scale_columns(sim.layout, k, c), True)
    np.testing.assert_array_equal(designs.parameters(0, 3), sim.scaled_parameter_sets(k, c))
    # and by hand: every isolator's damping doubled at c = 2
    scaled = sim.scaled_parameter_sets([1.0], [2.0])[0]
    for i, entry in enumerate(sim.layout.names):
        factor = 2.0 if (".damping." in entry or ".horizontal_damping." in entry) else (
            2.0 ** -0.25 if entry.endswith("orifice.diameter") else 1.0)
        assert scaled[i] == pytest.approx(sim.parameters[i] * factor, rel=1e-15)


def test_a_single_move_with_a_window_gives_moves_per_hour(tmp_path):
    path = tmp_path / "table-3-2-window.toml"
    path.write_text((DATA / "paper-table-3-2.toml").read_text() + WINDOW)
    sc = load_scenario(path)
    study = run_tradeoff_study(tmp_path / "out", sc, stiffness=K, damping=C, progress=False, workers=1)
    assert study.has_throughput
    assert (study.folder / "throughput.png").stat().st_size > 30_000
    sim = Simulator(replace(sc, simulation=replace(sc.simulation, duration=study.duration)))
    for i, j in ((0, 0), (1, 1), (2, 3)):
        run = sim.run(p=sim.scaled_parameters(K[i], C[j]))
        assert study.window_settling[i, j] == pytest.approx(run.window_settling_time_max, abs=1e-9)
        expected = moves_per_hour(run.stop_time - run.move_start, run.window_settling_time_max)
        assert study.per_hour[i, j] == pytest.approx(expected, rel=1e-9)
        assert study.settling_time[i, j] == pytest.approx(run.settling_time_max, abs=1e-9)
    front = study.throughput_pareto()
    assert front
    for p in front:  # nothing on the grid makes more moves per hour and isolates better
        better = (study.per_hour >= study.per_hour[p]) & (study.transmissibility <= study.transmissibility[p])
        strictly = (study.per_hour > study.per_hour[p]) | (study.transmissibility < study.transmissibility[p])
        assert not np.any(better & strictly)
    with open(study.folder / "designs.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert float(rows[5]["moves_per_hour"]) == pytest.approx(study.per_hour[1, 1], rel=1e-5)
    report = (study.folder / "report.md").read_text()
    assert "## Pareto-optimal designs in moves per hour" in report
    assert "![throughput](throughput.png)" in report


def test_the_study_runs_on_a_sequence_in_steps_per_hour(tmp_path):
    sc = load_scenario("paper-table-3-2-sequence")
    study = run_tradeoff_study(tmp_path, sc, stiffness=K, damping=C, progress=False)
    assert study.sequence
    assert (study.status == "ok").all()
    timed = replace(sc, simulation=replace(sc.simulation, duration=study.duration))
    sim = Simulator(sc)
    for i, j in ((0, 0), (1, 1), (2, 3)):
        one = run_sequence(timed, parameters=sim.scaled_parameters(K[i], C[j]))
        assert study.settling_time[i, j] == pytest.approx(one.total_time, abs=1e-9)
        assert study.per_hour[i, j] == pytest.approx(one.throughput, rel=1e-9)
    assert study.nominal() == (1, 1)
    assert np.all(np.diff(study.per_hour, axis=1) > 0)  # damping shortens every step's settling
    for name in ("maps.png", "tradeoff.png", "throughput.png"):
        assert (tmp_path / name).stat().st_size > 30_000
    report = (tmp_path / "report.md").read_text()
    assert "total time of the sequence" in report
    assert "steps per hour" in report
    with open(tmp_path / "designs.csv") as handle:
        header = next(csv.reader(handle))
    assert header[2:5] == ["total_time_s", "band", "steps_per_hour"]


def test_the_command_runs_the_quick_study_on_a_sequence(tmp_path, capsys):
    from isolator.cli.app import main

    assert main(["study", "tradeoff", "paper-table-3-2-sequence", "--out", str(tmp_path), "--quick",
                 "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert "Pareto-optimal designs of 12" in out
    assert "most steps per hour: " in out
    assert main(["study", "tradeoff", "--out", str(tmp_path), "--workers", "0"]) == 2
    assert capsys.readouterr().err.strip() == "isolator: error: --workers: must be a whole number >= 1, got 0"
