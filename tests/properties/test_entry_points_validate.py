"""Every public entry point refuses a bad argument with a ParameterError naming it (never numpy's or Python's).

Generated bad values (hypothesis) through the profile builders, move designs, profile settings, the
feedback designers, the sweeps' scale factors and ``linearise(positions=..., time=...)``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from conftest import active_dict, base_dict, make
from controllers import feedback as fb
from controllers.profiles.move_design import move_designs
from controllers.profiles.problem import ProfileSettings
from isolator import ParameterError, Simulator, linearise, samples, scurve, trapezoid

NOT_A_NUMBER = st.sampled_from([math.nan, math.inf, -math.inf, "fast", None, [1.0, 2.0], True])
NOT_POSITIVE = st.one_of(st.sampled_from([0.0, -1.0, -1e9]), NOT_A_NUMBER)
#: arguments whose None means "the default"
OPTIONAL = ("deceleration", "deceleration_jerk")
MOVE = {"start": 0.0, "stroke": 0.3, "velocity": 0.2, "acceleration": 1.0, "t0": 0.0}


def _names(error: pytest.ExceptionInfo, argument: str) -> None:
    assert str(error.value).startswith(f"{argument}: "), str(error.value)


@given(st.sampled_from(["velocity", "acceleration", "deceleration"]), NOT_POSITIVE)
def test_trapezoid_arguments(argument, value):
    assume(value is not None or argument not in OPTIONAL)
    with pytest.raises(ParameterError) as caught:
        trapezoid(**{**MOVE, argument: value})
    _names(caught, argument)


@given(st.sampled_from(["velocity", "acceleration", "jerk", "deceleration", "deceleration_jerk"]), NOT_POSITIVE)
def test_scurve_arguments(argument, value):
    assume(value is not None or argument not in OPTIONAL)
    with pytest.raises(ParameterError) as caught:
        scurve(**{**MOVE, "jerk": 20.0, argument: value})
    _names(caught, argument)


@given(st.sampled_from(["start", "stroke", "t0"]), st.sampled_from([math.nan, math.inf, "here"]))
def test_move_positions_and_start_times(argument, value):
    with pytest.raises(ParameterError) as caught:
        trapezoid(**{**MOVE, argument: value})
    _names(caught, argument)


def test_a_move_cannot_start_before_zero():
    with pytest.raises(ParameterError, match=r"^t0: must be >= 0, got -1$"):
        scurve(**{**MOVE, "jerk": 20.0, "t0": -1.0})


@given(st.sampled_from([([0.0, 1.0, 0.5], [0.0, 1.0, 2.0]), ([0.0], [1.0]), ([0.0, math.nan], [0.0, 1.0]),
                        ([-1.0, 1.0], [0.0, 1.0]), ([0.0, 1.0], [0.0]), ("abc", [0.0])]))
def test_sampled_moves(case):
    with pytest.raises(ParameterError) as caught:
        samples(*case)
    assert str(caught.value).split(":")[0] in ("t", "q", "t, q")


@given(st.sampled_from(["velocity", "acceleration", "deceleration", "jerk"]), NOT_POSITIVE)
def test_move_designs_built_directly(argument, value):
    design = move_designs(make(base_dict()), "scurve")[0]
    with pytest.raises(ParameterError) as caught:
        dataclasses.replace(design, **{argument: value})
    _names(caught, argument)


@given(st.sampled_from([("shooting_steps", 1.5), ("shooting_steps", 0), ("max_iterations", math.nan),
                        ("max_iterations", True), ("step_angle", "big"), ("step_angle", 0.0),
                        ("tolerance", -1.0), ("window_periods", None), ("shape", "sine"), ("screen", "yes"),
                        ("variants", ("nominal",)), ("max_move_time_increase", math.nan)]))
def test_profile_settings_on_construction(case):
    argument, value = case
    with pytest.raises(ParameterError) as caught:
        ProfileSettings(**{argument: value})
    _names(caught, argument)


@pytest.fixture(scope="module")
def active_plant():
    return linearise(make(active_dict()))


@given(st.sampled_from([("skyhook", "damping"), ("pid", "kp"), ("lead", "gain"), ("lqr", "max_displacement")]),
       st.sampled_from([math.nan, -1.0, "soft", None]))
def test_feedback_designers(active_plant, design, value):
    name, argument = design
    kwargs = {"lead": {"zero_hz": 5.0, "pole_hz": 50.0}}.get(name, {})
    with pytest.raises(ParameterError) as caught:
        getattr(fb, name)(active_plant, **{argument: value, **kwargs})
    _names(caught, argument)


@given(st.sampled_from([math.nan, "fast", None, -5.0]))
def test_controller_sample_rate(active_plant, value):
    with pytest.raises(ParameterError) as caught:
        fb.skyhook(active_plant, 1e3, sample_rate=value)
    _names(caught, "sample_rate")


@pytest.fixture(scope="module")
def simulator():
    return Simulator(make(base_dict()))


@given(st.sampled_from([("stiffness", "stiff"), ("stiffness", [1.0, "x"]), ("stiffness", True),
                        ("stiffness", 0.0), ("damping", -1.0), ("damping", math.nan)]))
def test_scale_factors(simulator, case):
    argument, value = case
    scales = {"stiffness": 1.0, "damping": 1.0, argument: value}
    with pytest.raises(ParameterError) as caught:
        simulator.scaled_parameter_sets(scales["stiffness"], scales["damping"])
    assert str(caught.value).startswith(argument)


@given(st.sampled_from([("positions", "abc"), ("positions", [math.nan]), ("positions", ["left"]),
                        ("positions", {"x-stage": "left"}), ("positions", {"x-stag": 0.1}),
                        ("time", "abc"), ("time", math.nan), ("time", -1.0)]))
def test_linearise_positions_and_time(case):
    argument, value = case
    with pytest.raises(ParameterError) as caught:
        linearise(make(base_dict()), **{argument: value})
    assert str(caught.value).startswith(argument)


def test_an_unknown_carriage_suggests_the_closest():
    with pytest.raises(ParameterError, match="did you mean 'x-stage'"):
        linearise(make(base_dict()), positions={"x-stag": 0.1})


def test_parameter_vectors_of_the_wrong_shape_or_kind(simulator):
    for bad in (simulator.parameters[:-1], np.zeros((2, simulator.layout.size)), "p", [1.0, "x"]):
        with pytest.raises(ParameterError, match=r"^p: must be a vector of"):
            simulator.run(p=bad)
