"""Hostile numbers and arguments (issue 35, items 8, 10 and 11): no silent nonsense, no raw Python or numpy
error, and the message names the real cause."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hostile_cases import refused
from hypothesis import given
from hypothesis import strategies as st

from conftest import base_dict
from isolator import IsolatorError, ParameterError, ScenarioError, linearise, load_scenario, scenario_from_dict
from isolator.analysis.modes import modes_over_travel
from isolator.analysis.transmissibility import transmissibility
from isolator.analysis.vibration import vibration_criteria
from isolator.model.signals import table_signals
from isolator.scenario.definitions import FloorSpectrum
from isolator.scenario.profile_shapes import scurve, segments, shaped, trapezoid
from isolator.scenario.rules import MOVE_FLOOR
from isolator.simulation.discrete_controller import DiscreteController
from isolator.simulation.settling import settling_time

TINY = st.floats(min_value=0.0, max_value=MOVE_FLOOR, exclude_min=True, exclude_max=True)


@given(which=st.sampled_from(["acceleration", "deceleration", "velocity"]), value=TINY)
def test_a_trapezoid_slower_than_any_stage_is_refused_naming_the_key(which, value):
    profile = {"type": "trapezoid", "start": -0.4, "stroke": 0.8, "velocity": 0.4, "acceleration": 1.0, which: value}
    data = base_dict()
    data["carriages"][0]["profile"] = profile
    with pytest.raises(ScenarioError, match=rf"^carriages\[0\]\.profile\.{which}: must be >= 1e-09"):
        scenario_from_dict(data)
    with pytest.raises(ParameterError, match=rf"^{which}: must be >= 1e-09"):
        trapezoid(-0.4, 0.8, **{"velocity": 0.4, "acceleration": 1.0, which: value})


@given(which=st.sampled_from(["jerk", "acceleration", "velocity"]), value=TINY)
def test_an_scurve_slower_than_any_stage_is_refused(which, value):
    with pytest.raises(ParameterError, match=rf"^{which}: must be >= 1e-09"):
        scurve(0.0, 0.8, **{"velocity": 0.4, "acceleration": 1.0, "jerk": 20.0, which: value})


def test_the_issue_trapezoids_no_longer_vanish_or_overflow():
    """acceleration = 1e-300 made the move vanish (stop 0.1 s, "does not move"); deceleration = 1e-300 was an
    OverflowError."""
    with pytest.raises(ParameterError, match="acceleration"):
        trapezoid(0.0, 0.8, 0.4, 1e-300, t0=0.1)
    with pytest.raises(ParameterError, match="deceleration"):
        trapezoid(0.0, 0.8, 0.4, 1.0, t0=0.1, deceleration=1e-300)
    slow = trapezoid(0.0, 0.8, 0.4, MOVE_FLOOR, t0=0.1)  # the slowest allowed still moves the whole stroke
    assert slow.stop_time == pytest.approx(0.1 + 2 * math.sqrt(0.8 / MOVE_FLOOR), rel=1e-9)
    assert slow.position(slow.stop_time) == pytest.approx(0.8, rel=1e-9)


@pytest.fixture(scope="module")
def lin():
    return linearise(load_scenario("paper-table-3-2"))


def _calls(lin):
    t = np.linspace(0.0, 1.0, 11)
    move = trapezoid(0.0, 0.8, 0.4, 1.0)
    ctrl = DiscreteController(1000.0, ["s"], ["a"], [], A=np.eye(1), B=np.ones((1, 1)), C=np.ones((1, 1)),
                              D=np.zeros((1, 1)))
    scene = load_scenario("paper-table-3-2")
    from controllers.feedback.export import write_c
    from controllers.feedforward.wrench import reaction_wrench

    return {
        "settling_time lengths": (lambda: settling_time(t, np.ones(5), 0.0, 0.5, 0.1), "s: 5 samples"),
        "settling_time NaN band": (lambda: settling_time(t, np.ones(11), 0.0, 0.5, math.nan), "band:"),
        "segments lengths": (lambda: segments(0.0, 0.0, [1.0], [1.0, 2.0], [0.0]), "accelerations:"),
        "segments text": (lambda: segments(0.0, 0.0, "abc", [1.0], [0.0]), "durations:"),
        "shaped": (lambda: shaped(move, [1.0], [0.1, 0.2]), "amplitudes, delays:"),
        "table_signals": (lambda: table_signals(np.ones((3, 5)), np.ones(2)), "states:"),
        "modes_over_travel": (lambda: modes_over_travel(scene, samples=0), "samples:"),
        "transmissibility 2-D": (lambda: transmissibility(lin, np.ones((3, 3))), "frequency_hz:"),
        "transmissibility 1e8": (lambda: transmissibility(lin, np.linspace(1.0, 100.0, 10**8)), "frequency_hz:"),
        "step": (lambda: ctrl.step(np.ones(3), np.ones(5)), "x:"),
        "from_dict": (lambda: DiscreteController.from_dict({"sample_rate": 1.0}), "controller.sensors"),
        "write_c": (lambda: write_c(ctrl, "/proc/nowhere/controller"), "folder:"),
        "reaction_wrench": (lambda: reaction_wrench(scene, np.ones(3), None, np.ones(2)), "rot:"),
        "trapezoid": (lambda: trapezoid(0.0, 0.8, 0.4, 1e-300), "acceleration:"),
    }


@pytest.mark.parametrize("name", [
    "settling_time lengths", "settling_time NaN band", "segments lengths", "segments text", "shaped",
    "table_signals", "modes_over_travel", "transmissibility 2-D", "transmissibility 1e8", "step",
    "from_dict", "write_c", "reaction_wrench", "trapezoid"])
def test_public_calls_raise_the_toolkits_own_error_naming_the_argument(lin, name):
    call, named = _calls(lin)[name]
    with pytest.raises(IsolatorError) as error:
        call()
    assert str(error.value).startswith(named), str(error.value)


def test_vibration_criteria_with_low_above_high_names_them(lin):
    spectrum = FloorSpectrum(kind="third-octave", frequency=np.array([1.0, 10.0, 100.0]),
                             values={"z": np.full(3, 1e-6)})
    with pytest.raises(ParameterError, match=r"^low, high: no one-third-octave band centre"):
        vibration_criteria(lin, spectrum, low=80, high=1)


def test_causes_are_named(tmp_path, monkeypatch, capsys):
    data = base_dict()
    data["table"]["mass"] = 5e-324
    with pytest.raises(ScenarioError, match=r"^table\.mass: "):  # was table.inertia[0]
        scenario_from_dict(data)
    data["table"]["mass"] = 10**400
    with pytest.raises(ScenarioError, match=r"^table\.mass: must be finite"):  # was a generic numerical failure
        scenario_from_dict(data)
    data = base_dict()
    data["carriages"][0]["profile"] = {"type": "sine", "amplitude": 0.01, "omega": 1e12}
    from isolator import Simulator

    with pytest.raises(ScenarioError, match=r"^carriages\[0\]\.profile\.omega: "):  # was blamed on the isolators
        Simulator(scenario_from_dict(data)).run()


def test_a_refused_simulate_leaves_no_folder_behind(tmp_path, monkeypatch, capsys):
    from hostile_cases import BASE

    monkeypatch.chdir(tmp_path)
    (tmp_path / "passwd").write_text("root:x:0:0:root:/root:/bin/bash\n", encoding="utf-8")
    line = refused(["simulate", str(BASE), "--forces", "passwd", "--out", "new/deep/r.csv"], capsys)
    assert line.startswith("--forces: ")
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize("argv", [["sweep", "--scale", "isolators[*].damping=1,2", "--samples", "4", "--seed", "-1",
                                   "--out", "s.csv"],
                                  ["simulate", "paper-table-3-2", "--noise", "--seed", "-1"]])
def test_a_negative_seed_is_one_line(tmp_path, monkeypatch, capsys, argv):
    monkeypatch.chdir(tmp_path)
    assert "--seed" in refused(argv, capsys)
