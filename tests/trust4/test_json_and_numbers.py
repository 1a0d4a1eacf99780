"""Trust round 4 (issue 42), item 5 and the 5,000-digit number of item 6: ``controller.json`` read by one
strict reader with one set of rules for every command; a whole number too long for Python one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import run_command
from isolator import ParameterError, load_scenario
from isolator.analysis.sampling import MAX_SAMPLE_RATE as MAX_STEPPING_RATE
from isolator.scenario.files import parse_json
from isolator.simulation.discrete_controller import DiscreteController

SCENARIO = "paper-table-3-2-geophones"


@pytest.fixture(scope="module")
def good() -> dict:
    scenario = load_scenario(SCENARIO)
    p, m = len(scenario.sensors), len(scenario.actuators)
    return DiscreteController(1000.0, [s.name for s in scenario.sensors], [x.name for x in scenario.actuators],
                              [c.name for c in scenario.carriages], A=0.5 * np.eye(1), B=np.full((1, p), 1e-3),
                              C=np.full((m, 1), 1e-3), D=np.zeros((m, p))).to_dict()


def _with_duplicate(data: dict, key: str, first: object) -> str:
    """``data`` as JSON with ``key`` given twice: first ``first``, then its value."""
    text = json.dumps(data)
    return text.replace("{", "{" + json.dumps(key) + ": " + json.dumps(first) + ", ", 1)


@given(key=st.sampled_from(["sample_rate", "sensors", "A", "method", "delay", "settings"]))
@settings(max_examples=10, deadline=None)
def test_a_key_given_twice_is_refused_naming_the_key_and_the_file(good, key, tmp_path_factory):
    path = tmp_path_factory.mktemp("c") / "controller.json"
    path.write_text(_with_duplicate(good, key, good[key]))
    with pytest.raises(ParameterError) as error:
        DiscreteController.from_json(path)
    message = str(error.value)
    assert message.startswith(str(path)), message
    assert f"'{key}' is given twice" in message, message


@given(key=st.text(st.characters(min_codepoint=32, max_codepoint=0x2FF), min_size=1, max_size=20),
       depth=st.integers(0, 3))
def test_parse_json_refuses_a_duplicate_at_any_depth(key, depth):
    inner = "{" + f"{json.dumps(key)}: 1, {json.dumps(key)}: 2" + "}"
    for _ in range(depth):
        inner = '{"x": [' + inner + "]}"
    with pytest.raises(ParameterError, match=r"^where: the key '.*' is given twice"):
        parse_json(inner, "where")


def test_the_budget_refuses_the_sample_rate_simulate_refuses(good, tmp_path, capsys):
    (tmp_path / "controller.json").write_text(json.dumps(dict(good, sample_rate=1e300)))
    for command in (["budget", SCENARIO], ["simulate", SCENARIO]):
        status, _, err = run_command([*command, "--controller", str(tmp_path)], capsys)
        assert (status, len(err)) == (2, 1), err
        assert err[0].startswith("isolator: error: --controller: "), err
        assert "sample_rate" in err[0], err
        assert f"at most {MAX_STEPPING_RATE:g} Hz" in err[0], err


@given(rate=st.floats(MAX_STEPPING_RATE, 1e308, exclude_min=True))
def test_a_controller_faster_than_any_stepping_grid_is_refused_whichever_way_it_is_made(good, rate):
    with pytest.raises(ParameterError, match=r"^sample_rate: must be a rate > 0 Hz and at most"):
        DiscreteController.from_dict(dict(good, sample_rate=rate))


def test_the_duplicate_key_reaches_the_command_line_as_one_line(good, tmp_path, capsys):
    (tmp_path / "controller.json").write_text(_with_duplicate(dict(good, sample_rate=2000.0), "sample_rate", 1))
    status, _, err = run_command(["simulate", SCENARIO, "--controller", str(tmp_path)], capsys)
    assert (status, len(err)) == (2, 1), err
    assert "'sample_rate' is given twice" in err[0], err
    assert str(tmp_path / "controller.json") in err[0]


@given(digits=st.integers(4301, 6000), where=st.sampled_from(["table", "simulation"]))
@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_a_number_of_thousands_of_digits_in_a_scenario_is_one_line_naming_the_file_and_key(
        digits, where, tmp_path_factory, capsys):
    base = Path(__file__).parents[1] / "bad_inputs" / "base.toml"
    path = tmp_path_factory.mktemp("s") / "huge.toml"
    key = {"table": "mass", "simulation": "duration"}[where]
    text = base.read_text()
    path.write_text(text.replace(f"[{where}]\n{key} = ", f"[{where}]\n{key} = {'7' * digits}\nx{key} = ", 1))
    status, _, err = run_command(["simulate", str(path)], capsys)
    assert (status, len(err)) == (2, 1), err
    assert str(path) in err[0], err
    assert f"'{key}' has {digits} digits" in err[0], err


def test_a_number_of_thousands_of_digits_in_controller_json(good, tmp_path):
    (tmp_path / "controller.json").write_text(json.dumps(good).replace("1000.0", "1" * 5000, 1))
    with pytest.raises(ParameterError, match="the number of 'sample_rate' has 5000 digits"):
        DiscreteController.from_json(tmp_path)
