"""The default designs on a bending top (issue 41, item 2: "where a design would be unstable or short of its
margins there, it rolls off its gain above the isolation band"): a design is made on the top's rigid-body model
and judged on the full plant. Made on the full plant, skyhook's root locus (the gain that damps the least-damped
pole most) answered to the elastic modes' 1 % damping and chose the grid's 10 N s/m, and the search then 2.5 N s/m:
practically no feedback. Here each default has the rigid-body design's gain in the isolation band, rolled off
above it where the full plant needs it, and the full plant's usual margins."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from controllers.feedback import check_robustness, design_controller, sensor_plant
from controllers.feedback.loop_margins import DiscreteResponse
from controllers.feedback.output_designs import skyhook_design
from controllers.feedback.output_tuning import DISK_MARGIN, GAIN_MARGIN, PHASE_MARGIN
from controllers.feedback.rolloff import lowpass, rigid_top
from isolator import Band, Simulator, load_scenario
from isolator.analysis.linear import linearise

SCENARIOS = Path(__file__).parents[2] / "isolator" / "data" / "scenarios"
RATE = 2000.0


def _bending(folder: Path, short: bool = False):
    """The geophones table on the bundled top's six lowest elastic modes (178 to 653 Hz on the isolators); short:
    a 0.2 m move in a 4 s run on its two lowest."""
    text = (SCENARIOS / "paper-table-3-2-geophones.toml").read_text()
    modes = (SCENARIOS / "paper-table-3-2-top-modes.csv").as_posix()
    count = 2 if short else 6
    text = text.replace("\n[[isolators]]", f'\n[table.flexible]\nmodes = "{modes}"\ncount = {count}\n'
                        "damping = 0.01\n\n[[isolators]]", 1)
    if short:
        text = text.replace("stroke = 1.4, velocity = 0.2, acceleration = 0.5, t0 = 0.5",
                            "stroke = 0.2, velocity = 0.2, acceleration = 0.5, t0 = 0.2")
        text = text.replace("stroke = 0.6, velocity = 0.083, acceleration = 0.5, t0 = 0.5",
                            "stroke = 0.05, velocity = 0.083, acceleration = 0.5, t0 = 0.2")
        text = re.sub(r"^duration = .*$", "duration = 4.0", text, count=1, flags=re.M)
    path = folder / f"bending{'-short' if short else ''}.toml"
    path.write_text(text)
    return load_scenario(path)


@pytest.fixture(scope="module")
def bending(tmp_path_factory):
    return _bending(tmp_path_factory.mktemp("bending"))


def _gain_at(ctrl, f: float) -> np.ndarray:
    """The controller's frequency response at ``f`` [Hz] (actuators, sensors)."""
    return DiscreteResponse(*ctrl.matrices())(np.array([np.exp(2j * math.pi * f / ctrl.sample_rate)]))[0]


def _keeps_the_usual_margins(scenario, ctrl) -> None:
    report = check_robustness(scenario, ctrl).to_dict()
    assert report["stable"]
    gain = report["worst_gain_margin"]["gain_margin"]
    phase = report["worst_phase_margin"]["phase_margin"]
    assert report["worst_disk_margin"]["disk_margin"] >= DISK_MARGIN
    assert gain is None or gain >= GAIN_MARGIN
    assert phase is None or phase >= PHASE_MARGIN


def test_skyhooks_root_locus_is_the_rigid_body_models(bending):
    made = design_controller(bending, "skyhook", RATE, search=False)
    rigid = design_controller(rigid_top(bending), "skyhook", RATE, search=False)
    assert made.settings["points"][0]["gain"] == rigid.settings["points"][0]["gain"]
    assert made.settings["points"][0]["gain"] > 1e4  # N s/m: damping the isolation modes
    # what the root locus on the full plant chooses: the grid's least gain (the elastic modes' 1 % decides)
    full = skyhook_design(sensor_plant(linearise(bending)), RATE)
    assert full.settings["gain"] == 10.0
    _keeps_the_usual_margins(bending, made)


@pytest.mark.parametrize(("method", "delay"), [("skyhook", True), ("lqg", False), ("lqg", True), ("hinf", False),
                                               ("hinf", True)])
def test_each_default_keeps_its_gain_in_the_band_and_the_margins_on_the_full_plant(bending, method, delay):
    """The bending top's design is the rigid-body design followed by its roll-off (where the full plant needs
    one): the same gain per reading at 2 Hz, in the isolation band, and the usual margins on the full plant.
    (Unsearched: the search on a bending top is the slow test below.)"""
    made = design_controller(bending, method, RATE, delay=delay, search=False)
    rigid = design_controller(rigid_top(bending), method, RATE, delay=delay, search=False)
    record = made.settings.get("rolloff")
    for f in (2.0, 400.0):  # the rigid-body design, then the roll-off (or nothing)
        k_made, k_rigid = _gain_at(made, f), _gain_at(rigid, f)
        if record is not None:
            a, b, c, d = lowpass(record["corner_hz"], RATE, len(bending.actuators))
            z = np.exp(2j * math.pi * f / RATE)
            k_rigid = (c @ np.linalg.solve(z * np.eye(a.shape[0]) - a, b) + d) @ k_rigid
        np.testing.assert_allclose(k_made, k_rigid, rtol=1e-6, atol=1e-9 * np.abs(k_rigid).max())
    k_made, k_rigid = _gain_at(made, 2.0), _gain_at(rigid, 2.0)
    assert np.linalg.norm(np.abs(k_made) - np.abs(k_rigid)) < 0.01 * np.linalg.norm(k_rigid)  # the band's gain
    if record is not None:  # rolled off above the isolation band, below the lowest elastic mode
        assert 30.0 <= record["corner_hz"] <= 0.5 * record["lowest_elastic_mode_hz"] + 1e-9
        assert "insufficient" not in record
        assert np.linalg.norm(_gain_at(made, 400.0)) < 0.2 * np.linalg.norm(_gain_at(rigid, 400.0))
    _keeps_the_usual_margins(bending, made)


@pytest.mark.slow
def test_the_skyhook_search_on_a_bending_top_finds_useful_damping(tmp_path):
    """The search (each candidate's move simulated on the full plant, about 20 of them) on a short move: its
    gains are of the rigid-body design's order and the move settles in a fraction of the passive time."""
    scenario = _bending(tmp_path, short=True)
    made = design_controller(scenario, "skyhook", RATE)
    search = made.settings["search"]
    assert min(made.settings["gain"]) > 5e3  # N s/m on every axis
    assert search["settling"] < 0.5 * search["passive_settling"]
    _keeps_the_usual_margins(scenario, made)
    sim = Simulator(scenario)
    band = Band.of_baseline("passive", sim.run().peak)
    assert sim.run(controller=made).with_band(band).settling_time_max == pytest.approx(search["settling"], rel=1e-6)
