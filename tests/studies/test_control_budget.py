"""The control study's error budget (issue 32, "what it buys"): for a sensor-based design, the budget at the tool
passive and closed loop in one band, the part its sensors' noise adds (linear in the noise's PSD, the squares
adding up to the total), the figure's labels and legends, the report's table, the floor option and its refusal."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from conftest import run_command as run
from isolator import load_scenario
from isolator.analysis.budget import budget_band, error_budget
from isolator.errors import ScenarioError
from isolator.scenario.random_sources import SpectralDensity
from isolator.simulation.discrete_controller import DiscreteController
from studies import control_budget
from studies.control_budget import budget_figure, budget_section, design_budget, on_floor

RATE = 2000.0


def skyhook(scenario, gain: float = 3.0e4) -> DiscreteController:
    """Velocity feedback from each geophone to its collocated actuator (the bundled table's pairs, in order)."""
    n = len(scenario.sensors)
    return DiscreteController(RATE, [s.name for s in scenario.sensors], [a.name for a in scenario.actuators],
                              [c.name for c in scenario.carriages], method="skyhook", A=np.zeros((0, 0)),
                              B=np.zeros((0, n)), C=np.zeros((n, 0)),
                              D=-gain * np.eye(n))


@pytest.fixture(scope="module")
def scenario():
    return load_scenario("paper-table-3-2-budget")


@pytest.fixture(scope="module")
def budget(scenario):
    return design_budget(scenario, skyhook(scenario))


def test_passive_and_closed_loop_in_the_closed_loops_band(scenario, budget):
    assert budget.available
    assert budget.point == "probe"
    band = budget_band(None, skyhook(scenario))
    assert budget.passive.band == budget.closed.band == band  # compared in one band
    assert budget.passive.value("probe", "z") == pytest.approx(
        error_budget(scenario, points=["probe"], band=band).value("probe", "z"), rel=1e-12)
    assert not any(s.startswith("sensor:") for s in budget.passive.sources)
    assert sum(s.startswith("sensor:") for s in budget.closed.sources) == len(scenario.sensors)
    # velocity feedback damps the isolation modes: less random motion at the tool on every axis
    assert np.all(budget.closed.rms[0] < budget.passive.rms[0])


def test_the_sensor_noise_part_is_the_sensors_sources_and_scales_with_their_psd(scenario, budget):
    sensor = budget.sensor_rms()
    parts = budget.closed.source_rms[0]
    noisy = [k for k, s in enumerate(budget.closed.sources) if s.startswith("sensor:")]
    assert np.allclose(sensor ** 2, (parts[:, noisy] ** 2).sum(axis=1), rtol=1e-9)
    assert np.all(sensor < budget.closed.rms[0])
    # four times the noise's PSD: twice its RMS at the tool, the rest of the budget unchanged
    louder = replace(scenario, sensors=tuple(
        replace(s, noise_psd=SpectralDensity(tuple(4 * v for v in s.noise_psd.value), s.noise_psd.frequency))
        for s in scenario.sensors))
    again = design_budget(louder, skyhook(louder))
    assert np.allclose(again.sensor_rms(), 2 * sensor, rtol=1e-3)
    rest = np.sqrt(budget.closed.rms[0] ** 2 - sensor ** 2)
    assert np.allclose(np.sqrt(again.closed.rms[0] ** 2 - again.sensor_rms() ** 2), rest, rtol=1e-3)
    # a geophone's noise rises below 10 Hz: half its square at the tool lies below the isolation modes (~3 Hz)
    half = budget.sensor_half_frequency()
    assert np.all((half > budget.closed.band[0]) & (half < 3.0))


def test_a_scenario_without_random_sources_has_a_note_and_a_floor_gives_one(scenario):
    geophones = load_scenario("paper-table-3-2-geophones")
    ctrl = skyhook(geophones)
    none = design_budget(geophones, ctrl)
    assert not none.available
    assert "needs a floor spectrum" in none.note
    assert none.to_dict() == {"point": "table", "note": none.note}
    assert budget_section({"skyhook": none})[2].startswith("No budget: the scenario has no random source")
    floored = design_budget(on_floor(geophones, "VC-D"), ctrl)
    assert floored.available
    assert floored.passive.sources == ("floor:x", "floor:y", "floor:z")
    # the same table on the same floor as the bundled budget scenario: the floor's part at the mass centre agrees
    # (each budget's grid is refined for its own sources: within the budget's accuracy)
    table = replace(scenario, points=())
    own = error_budget(table, points=["table"], band=floored.passive.band)
    for axis in "xyz":
        floor = math.sqrt(sum(own.value("table", axis, f"floor:{a}") ** 2 for a in "xyz"))
        assert floored.passive.value("table", axis) == pytest.approx(floor, rel=2e-3)
    with pytest.raises(ScenarioError, match="floor: unknown vibration criterion 'VC-Z'"):
        on_floor(geophones, "VC-Z")


def test_the_figure_labels_and_legends(budget, monkeypatch, tmp_path):
    figures = []
    monkeypatch.setattr(control_budget, "save_figure", lambda fig, path: figures.append((fig, path)))
    budget_figure({"skyhook": budget}, tmp_path / "sensors-budget.png")
    (fig, path), = figures
    assert path.name == "sensors-budget.png"
    bars, *spectra = fig.axes
    assert bars.get_ylabel() == "displacement RMS [nm]"
    assert [t.get_text() for t in bars.get_xticklabels()] == ["x", "y", "z"]
    assert [t.get_text() for t in bars.get_legend().get_texts()] == [
        "passive", "skyhook: closed loop, total", "skyhook: of which its sensors' noise"]
    heights = [p.get_height() for p in bars.patches]
    assert np.allclose(heights[:3], budget.passive.rms[0] * 1e9)
    assert np.allclose(heights[3:6], budget.closed.rms[0] * 1e9)
    assert np.allclose(heights[6:9], budget.sensor_rms() * 1e9)
    for axis, ax in zip("xyz", spectra, strict=True):
        assert ax.get_xlabel() == "frequency [Hz]"
        assert ax.get_ylabel() == f"{axis}: displacement ASD [nm/√Hz]"
        assert [t.get_text() for t in ax.get_legend().get_texts()] == [
            "passive", "skyhook: closed loop", "skyhook: its sensors' noise"]
    assert fig.get_suptitle().startswith("Error budget at probe")


def test_the_report_table(budget):
    lines = budget_section({"skyhook": budget})
    rows = [line for line in lines if line.startswith("| skyhook |")]
    assert len(rows) == 3
    cells = [c.strip() for c in rows[2].strip("|").split("|")]
    assert cells[:2] == ["skyhook", "z"]
    passive, closed, through, noise = (float(c) for c in cells[2:6])
    assert passive == pytest.approx(budget.passive.value("probe", "z") * 1e9, rel=1e-3)
    assert closed == pytest.approx(budget.closed.value("probe", "z") * 1e9, rel=1e-3)
    assert math.hypot(through, noise) == pytest.approx(closed, rel=2e-3)
    assert budget.to_dict()["axes"]["z"]["sensor_noise_rms"] == pytest.approx(budget.sensor_rms()[2])


def test_a_bad_floor_on_the_command_line_is_one_line_and_nothing_written(tmp_path, capsys):
    out = tmp_path / "study"
    status, _, err = run(["study", "control", "--floor", "VC-Z", "--out", str(out)], capsys)
    assert status == 2
    assert len(err) == 1, err
    assert "--floor: unknown vibration criterion 'VC-Z'" in err[0]
    assert not out.exists()
