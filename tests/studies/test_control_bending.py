"""The control study's bending-top case (issue 41, item 3), reduced as the study's ``--quick`` runs it: the
default designs on the rigid and the bending top, the corner's compliance open and closed loop, a stiff design the
check refuses with its growing mode."""

from __future__ import annotations

import math
import tomllib
from importlib.resources import files

import numpy as np
import pytest

from controllers.feedback import design_controller
from isolator import Band, ScenarioError, Simulator, load_scenario, scenario_from_dict
from isolator.analysis.closed_loop import check_controller
from isolator.analysis.linear import linearise
from isolator.analysis.point_compliance import point_compliance
from isolator.cli.app import main
from isolator.simulation.actuation import ForceHistory
from studies import control_bending_report
from studies.control_bending import STIFF_GAIN, bending_pair, closed_loop_compliance, run_bending_case

SCENARIO = "paper-table-3-2-geophones"


@pytest.fixture(scope="module")
def case():
    scenario = load_scenario(SCENARIO)
    band = Band.of_baseline("passive", Simulator(scenario).run().peak)
    return run_bending_case(scenario, band, quick=True)


def test_the_pair_differs_only_in_the_top():
    rigid, bending = bending_pair(load_scenario(SCENARIO))
    assert rigid.table.flexible is None
    assert bending.table.flexible is not None
    assert [p.name for p in rigid.points] == [p.name for p in bending.points] == ["corner"]
    assert rigid.points[0].position == (1.0, 0.5, 0.15)
    assert (rigid.sensors, rigid.actuators, rigid.carriages) == (bending.sensors, bending.actuators, bending.carriages)
    again_rigid, again_bending = bending_pair(bending)  # a bending scenario: its rigid twin
    assert again_rigid.table.flexible is None
    assert again_bending is bending


def _geophones() -> dict:
    return tomllib.loads((files("isolator") / "data" / "scenarios" / f"{SCENARIO}.toml").read_text())


def test_a_table_the_bundled_top_does_not_fit_is_refused_in_one_line(tmp_path, capsys):
    data = _geophones()
    data["table"]["mass"] = 4000.0
    with pytest.raises(ScenarioError, match=r"^table\.flexible: the control study's bending-top case"):
        bending_pair(scenario_from_dict(data))
    # refused before the study's runs
    assert main(["study", "control", "paper-table-3-2-active", "--bending", "--quick", "--out", str(tmp_path)]) == 2
    assert "sensors: the bending-top case compares sensor-based designs" in capsys.readouterr().err


def test_both_tops_get_each_design_with_settling_and_margins(case):
    assert [(d.method, d.top) for d in case.designs] == [("skyhook", "rigid"), ("skyhook", "bending")]
    rigid, bending = case.design("skyhook", "rigid"), case.design("skyhook", "bending")
    gain = bending.to_dict()["gain"]
    assert gain > 1e4  # useful damping, the rigid-body model's root locus (not the elastic modes' near-zero gain)
    assert rigid.settling is not None
    assert bending.settling is not None
    assert bending.settling == pytest.approx(rigid.settling, rel=0.2)  # the modes barely change the move's settling
    assert bending.robustness["stable"]
    assert bending.margin("disk_margin") >= 0.5
    assert bending.margin("disk_margin") < rigid.margin("disk_margin")  # the elastic modes eat margin
    for d in case.designs:  # the table's number is the robustness check's worst case
        assert d.to_dict()["spectral_radius"] == max(c["spectral_radius"] for c in d.robustness["cases"])


def test_the_open_loop_compliance_is_isolator_compliance(case):
    rigid, bending = bending_pair(load_scenario(SCENARIO))
    f = case.frequency_hz
    for top, scenario in (("rigid", rigid), ("bending", bending)):
        expected = point_compliance(linearise(scenario), "corner", "z", frequency_hz=f).response_values
        np.testing.assert_allclose(case.compliance[f"{top}, open"], expected, rtol=1e-6)
    closed, open_ = np.abs(case.compliance["bending, closed (skyhook)"]), np.abs(case.compliance["bending, open"])
    rigid_band = f < 10.0
    assert closed[rigid_band].max() < 0.8 * open_[rigid_band].max()  # skyhook damps the rigid-body peaks
    lowest = min(case.elastic_hz.values())
    near = (f > 0.9 * lowest) & (f < 1.3 * lowest)
    assert open_[near].max() > 3 * np.abs(case.compliance["rigid, open"])[near].max()  # the top's own peaks


def test_the_closed_loop_compliance_equals_a_simulated_force_sine():
    """A sine force through actuator z1 (its lag divided out) on the still rigid table with skyhook in the loop:
    the displacement at z1's point is the closed-loop compliance there."""
    data = _geophones()
    data["carriages"] = []
    data["simulation"] = {"duration": 6.0, "sample_rate": 1000.0}
    data["points"] = [{"name": "at-z1", "position": [1.0, 0.5, -0.15]}]
    scenario = scenario_from_dict(data)
    ctrl = design_controller(scenario, "skyhook", 2000.0)
    f0, amplitude = 4.0, 100.0
    t = np.arange(0.0, 6.0 + 1e-9, 1e-4)
    forces = np.zeros((len(scenario.actuators), t.size))
    forces[2] = amplitude * np.sin(2 * math.pi * f0 * t)
    names = tuple(a.name for a in scenario.actuators)
    run = Simulator(scenario).run(controller=ctrl, forces=ForceHistory(t, forces, names))
    tail = run.t > 3.0
    w = 2 * math.pi * f0
    basis = np.column_stack([np.sin(w * run.t[tail]), np.cos(w * run.t[tail]), np.ones(tail.sum())])
    coef = np.linalg.lstsq(basis, run.point("at-z1")[2][tail], rcond=None)[0]
    lag = 1.0 / (1.0 + 1j * f0 / scenario.actuators[2].bandwidth)
    measured = complex(coef[0], coef[1]) / (amplitude * lag)  # sin -> 1, cos -> j
    predicted = closed_loop_compliance(linearise(scenario), "at-z1", "z", np.array([f0]), ctrl)[0]
    passive = closed_loop_compliance(linearise(scenario), "at-z1", "z", np.array([f0]))[0]
    assert abs(measured - predicted) < 0.02 * abs(predicted)
    assert abs(predicted - passive) > 0.2 * abs(passive)  # the loop changes it: the check can tell


def test_the_stiff_design_is_refused_on_the_bending_top_with_its_growing_mode(case):
    stiff = case.stiff
    assert stiff.gain == STIFF_GAIN
    assert stiff.rigid.stable
    assert not stiff.bending.stable
    rigid, bending = bending_pair(load_scenario(SCENARIO))
    alone = check_controller(bending, design_controller(rigid, "skyhook", 2000.0, delay=True,
                                                        options={"gain": STIFF_GAIN}))
    assert stiff.bending.spectral_radius == pytest.approx(alone.spectral_radius, rel=1e-12)
    assert (stiff.mode, stiff.mode_hz) == alone.growing_mode()
    assert stiff.mode in case.elastic_hz  # an elastic mode grows, at about its frequency
    assert stiff.bending.frequency_hz == pytest.approx(case.elastic_hz[stiff.mode], rel=0.05)
    assert stiff.rolled.settings["rolloff"]["kind"] == "low-pass"
    assert stiff.rolled_loop.stable
    lines = control_bending_report.bending_report(case)
    text = "\n".join(lines)
    assert f"from the open-loop mode '{stiff.mode}' ({stiff.mode_hz:.4g} Hz)" in text
    assert "| skyhook | bending |" in text


def test_the_figures_have_axes_units_and_legends(case, tmp_path, monkeypatch):
    kept = {}
    monkeypatch.setattr(control_bending_report, "save_figure", lambda fig, path: kept.__setitem__(path.name, fig))
    control_bending_report.bending_figures(case, tmp_path)
    assert set(kept) == set(control_bending_report.FIGURES)
    settling, disk, phase = kept["bending-defaults.png"].axes
    heights = [bar.get_height() for bar in settling.patches]
    assert heights == pytest.approx([case.design("skyhook", top).settling for top in ("rigid", "bending")])
    assert [bar.get_height() for bar in disk.patches] == pytest.approx(
        [case.design("skyhook", top).margin("disk_margin") for top in ("rigid", "bending")])
    assert "[s]" in settling.get_ylabel()
    assert "[-]" in disk.get_ylabel()
    assert "[deg]" in phase.get_ylabel()
    (ax,) = kept["bending-compliance.png"].axes
    assert ax.get_xlabel() == "frequency [Hz]"
    assert "[m/N]" in ax.get_ylabel()
    labels = [line.get_label() for line in ax.get_lines()]
    assert {"rigid, open loop", "bending, open loop", "rigid, closed (skyhook)", "bending, closed (skyhook)"} <= \
        set(labels)
