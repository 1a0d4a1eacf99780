"""``[[windows]]`` keys: read, defaults, and every bad value one error naming its key."""

from __future__ import annotations

import copy
import dataclasses
import re
from typing import Any

import pytest

from conftest import base_dict
from isolator import scenario_from_dict
from isolator.errors import ScenarioError
from isolator.scenario.validation import validate_scenario
from isolator.scenario.windows import Window

PROBE = {"name": "probe", "position": [0.3, 0.0, 0.45]}


def _data(*windows: dict[str, Any], **extra: Any) -> dict[str, Any]:
    return base_dict(points=[PROBE], windows=list(windows), **extra)


def _error(data: dict[str, Any]) -> str:
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(copy.deepcopy(data))
    return str(info.value)


def test_windows_read_with_default_axes():
    sc = scenario_from_dict(_data({"point": "probe", "translation": 5e-8},
                                  {"point": "probe", "translation": 1e-7, "axes": ["z", "x"]}))
    assert sc.windows == (Window("probe", 5e-8, ("x", "y", "z")), Window("probe", 1e-7, ("z", "x")))
    assert sc.windows[1].axis_indices == (2, 0)
    assert scenario_from_dict(base_dict()).windows == ()


@pytest.mark.parametrize(("window", "key", "words"), [
    ({"point": "lens", "translation": 5e-8}, "windows[0].point", "unknown point 'lens'"),
    ({"point": "probe", "translation": 0.0}, "windows[0].translation", "> 0"),
    ({"point": "probe", "translation": -1e-8}, "windows[0].translation", "> 0"),
    ({"point": "probe", "translation": "5e-8"}, "windows[0].translation", "number"),
    ({"point": "probe", "translation": 5e-8, "axes": ["x", "w"]}, "windows[0].axes[1]", "unknown axis 'w'"),
    ({"point": "probe", "translation": 5e-8, "axes": []}, "windows[0].axes", "at least one"),
    ({"point": "probe", "translation": 5e-8, "axes": ["x", "x"]}, "windows[0].axes[1]", "twice"),
    ({"point": "probe", "translation": 5e-8, "axes": "x"}, "windows[0].axes", "list"),
    ({"point": "probe"}, "windows[0].translation", "missing"),
    ({"translation": 5e-8}, "windows[0].point", "missing"),
    ({"point": "probe", "translation": 5e-8, "axis": ["x"]}, "windows[0].axis", "unknown key"),
])
def test_bad_window_is_named(window, key, words):
    message = _error(_data(window))
    assert message.startswith(f"{key}:"), message
    assert words in message, message


def test_window_without_points_is_named():
    message = _error(base_dict(windows=[{"point": "probe", "translation": 5e-8}]))
    assert re.match(r"windows\[0\]\.point: unknown point 'probe' \(points: none declared", message), message


def test_windows_must_be_an_array_of_tables():
    assert _error(base_dict(points=[PROBE], windows={"point": "probe"})).startswith("windows:")


def test_sequence_with_a_carriage_profile_is_refused():
    """``[sequence]`` is read now (tests/scenario/test_sequence_input.py); a carriage profile beside it is not."""
    message = _error(_data(sequence={"measure": 0.1, "steps": [{"x-stage": 0.1}]}))
    assert message.startswith("carriages[0].profile: with [sequence] the carriages give no profile"), message


def test_scenarios_built_from_dataclasses_are_checked_too():
    sc = scenario_from_dict(_data({"point": "probe", "translation": 5e-8}))
    for bad, key in ((Window("lens", 5e-8), "windows[0].point"), (Window("probe", -1.0), "windows[0].translation"),
                     (Window("probe", 5e-8, ("q",)), "windows[0].axes[0]")):
        with pytest.raises(ScenarioError, match=re.escape(key)):
            validate_scenario(dataclasses.replace(sc, windows=(bad,)))
