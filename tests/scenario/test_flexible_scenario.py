"""``[table.flexible]`` and ``feet`` in a scenario: read from TOML, checked by the rules and against the table,
everything on the top within its faces, written back, built in Python; a scenario without them unchanged."""

from __future__ import annotations

import copy
import dataclasses
import pickle
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import tomli_w

from conftest import base_dict
from isolator import load_scenario, scenario_from_dict
from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.definitions import Carriage, Point, Scenario, Table
from isolator.scenario.flexible import FlexibleTop, load_flexible
from isolator.scenario.flexible.synthetic import synthetic_top
from isolator.scenario.flexible.writing import flexible_toml, write_modal_csv
from isolator.scenario.validation import validate_scenario
from isolator.scenario.writing import scenario_data, write_toml

MASS = 4400.0
SIZE = (2.0, 1.0, 0.3)


@pytest.fixture
def modes(tmp_path) -> Path:
    top = synthetic_top(SIZE, MASS, frequencies=(120.0, 180.0, 250.0))
    return write_modal_csv(tmp_path / "top-modes.csv", top.frequencies, top.nodes, top.translations)


def _data(modes: Path, **flexible: Any) -> dict[str, Any]:
    data = base_dict()
    data["table"]["flexible"] = {"modes": modes.name, **flexible}
    return data


def _load(data: dict[str, Any], folder: Path) -> Scenario:
    return scenario_from_dict(copy.deepcopy(data), base_dir=folder)


def _error(data: dict[str, Any], folder: Path) -> str:
    with pytest.raises(ScenarioError) as info:
        _load(data, folder)
    return str(info.value)


def test_a_scenario_file_with_a_bending_top_loads(tmp_path, modes):
    data = _data(modes, count=2, damping=0.02, origin=[0.0, 0.0, 0.0])
    data["carriages"][0]["feet"] = [[0.0, 0.4], [0.0, -0.4]]
    data["points"] = [{"name": "tool", "position": [0.3, 0.0, 0.5], "feet": [[-0.5, 0.0], [0.5, 0.0]]}]
    path = tmp_path / "flex.toml"
    path.write_text(tomli_w.dumps(data))
    scenario = load_scenario(path)
    flexible = scenario.table.flexible
    assert flexible.modes == "top-modes.csv"
    assert (flexible.count, flexible.damping, flexible.origin) == (2, 0.02, (0.0, 0.0, 0.0))
    assert scenario.modal_data is flexible.data
    np.testing.assert_array_equal(scenario.modal_data.frequencies, [120.0, 180.0])
    np.testing.assert_array_equal(scenario.modal_data.damping, [0.02, 0.02])
    assert scenario.carriages[0].feet == ((0.0, 0.4), (0.0, -0.4))
    assert scenario.points[0].feet == ((-0.5, 0.0), (0.5, 0.0))
    assert scenario.modal_data.rigid.mass == pytest.approx(MASS)
    assert load_scenario(path) == scenario  # equal by content; hashable
    assert hash(load_scenario(path).table) == hash(scenario.table)
    assert pickle.loads(pickle.dumps(scenario)) == scenario


def test_a_scenario_without_the_keys_is_unchanged():
    scenario = load_scenario("paper-table-3-2")
    assert scenario.table.flexible is None
    assert scenario.modal_data is None
    assert all(c.feet is None for c in scenario.carriages)
    rigid = scenario_from_dict(base_dict())
    table = rigid.table
    assert table == Table(mass=table.mass, inertia=table.inertia, size=table.size)
    c = rigid.carriages[0]
    assert c == Carriage(c.name, c.mass, c.parent, c.axis, c.origin, c.profile, c.limits)
    assert validate_scenario(rigid) is rigid


@pytest.mark.parametrize(("keys", "message"), [
    ({"count": 0}, "table.flexible.count: must be > 0, got 0"),
    ({"count": 1.5}, "table.flexible.count: must be a whole number, got 1.5"),
    ({"count": 4}, "table.flexible.count: 4 elastic modes asked, but table.flexible.modes: '"),
    ({"max_frequency": 0.0}, "table.flexible.max_frequency: must be > 0, got 0"),
    ({"max_frequency": 100.0}, "table.flexible.max_frequency: 100 Hz leaves no elastic mode of"),
    ({"damping": 1.0}, "table.flexible.damping: must be < 1, got 1"),
    ({"damping": -0.1}, "table.flexible.damping: must be >= 0, got -0.1"),
    ({"origin": [0.0, 0.0]}, "table.flexible.origin: must be a list of three numbers"),
    ({"origin": [0.0, float("nan"), 0.0]}, "table.flexible.origin[1]: must be finite, got nan"),
    ({"modez": "x.csv"}, "table.flexible.modez: unknown key"),
    ({"mode": 1}, "table.flexible.mode: unknown key; did you mean 'modes'?"),
])
def test_bad_keys_are_refused_naming_them(tmp_path, modes, keys, message):
    assert _error(_data(modes, **keys), tmp_path).startswith(message)


def test_a_missing_file_and_a_table_of_another_mass_are_refused(tmp_path, modes):
    data = _data(modes)
    data["table"]["flexible"]["modes"] = "nothing.csv"
    assert _error(data, tmp_path) == f"table.flexible.modes: cannot read '{tmp_path / 'nothing.csv'}' (no such file)"
    data = _data(modes)
    data["table"]["mass"] = 5000.0
    assert _error(data, tmp_path).startswith(f"table.flexible.modes: '{modes}': its six rigid modes give a top of "
                                             "mass 4400 kg, [table] mass is 5000 kg")
    data = _data(modes, origin=[0.0, 0.05, 0.0])
    assert "mass centre at [0, 0.05, 0] m in the table frame" in _error(data, tmp_path)


@pytest.mark.parametrize(("feet", "message"), [
    ([], "carriages[0].feet: must be a non-empty list of [x, y] offsets (m)"),
    ("left", "carriages[0].feet: must be a non-empty list"),
    ([[0.0, 0.1, 0.2]], "carriages[0].feet[0]: must be [x, y], two numbers (m)"),
    ([[0.0, 0.1], 3.0], "carriages[0].feet[1]: must be [x, y]"),
    ([[0.0, "a"]], "carriages[0].feet[0][1]: must be a number, got 'a'"),
    ([[0.0, float("inf")]], "carriages[0].feet[0][1]: must be finite, got inf"),
])
def test_bad_feet_are_refused(tmp_path, modes, feet, message):
    data = _data(modes)
    data["carriages"][0]["feet"] = feet
    assert _error(data, tmp_path).startswith(message)


def test_feet_on_a_carriage_riding_another_are_refused(tmp_path, modes):
    data = _data(modes)
    data["carriages"].append({"name": "y-stage", "mass": 40.0, "parent": "x-stage", "axis": [0.0, 1.0, 0.0],
                              "origin": [0.0, 0.0, 0.1], "feet": [[0.1, 0.0]],
                              "profile": {"type": "sine", "amplitude": 0.1, "omega": 1.0}})
    assert _error(data, tmp_path).startswith("carriages[1].feet: carriage 'y-stage' rides its parent 'x-stage'")


def test_a_foot_off_the_top_anywhere_along_the_travel_is_refused(tmp_path, modes):
    """The carriage travels from q = -0.4 to 0.4 m: a foot 0.65 m ahead of it leaves the top only at the end."""
    data = _data(modes)
    data["carriages"][0]["feet"] = [[0.0, 0.4], [0.65, -0.4]]
    assert _error(data, tmp_path).startswith(
        "carriages[0] (x-stage).feet[1] (at q = 0.4 m): (x, y) = (1.05, -0.4) m lies 50 mm outside the top face of "
        "the top's nodes")
    data["carriages"][0]["feet"] = [[0.0, 0.4], [0.6, -0.4]]
    assert _load(data, tmp_path).carriages[0].feet[1] == (0.6, -0.4)


@pytest.mark.parametrize(("section", "item", "what"), [
    ("points", {"name": "tool", "position": [1.2, 0.0, 0.5]}, "points[0] (tool).position: (x, y) = (1.2, 0) m"),
    ("points", {"name": "tool", "position": [0.0, 0.0, 0.5], "feet": [[0.0, 0.6]]},
     "points[0] (tool).feet[0]: (x, y) = (0, 0.6) m lies 100 mm outside the top face"),
    ("actuators", {"name": "a", "position": [1.1, 0.5, -0.15], "direction": [0, 0, 1], "max_force": 100.0},
     "actuators[0] (a).position: (x, y) = (1.1, 0.5) m lies 100 mm outside the bottom face"),
])
def test_things_fixed_to_the_top_off_its_faces_are_refused(tmp_path, modes, section, item, what):
    data = _data(modes)
    data[section] = [item]
    assert _error(data, tmp_path).startswith(what)


def test_the_scenario_written_back_elsewhere_loads_the_same_modes(tmp_path, modes):
    source = tmp_path / "flex.toml"
    source.write_text(tomli_w.dumps(_data(modes, count=2)))
    _, data = scenario_data(source)
    assert data["table"]["flexible"]["modes"] == str(modes.resolve())
    copy_path = write_toml(data, tmp_path / "elsewhere" / "copy.toml")
    assert load_scenario(copy_path) == load_scenario(source)
    keys = flexible_toml(load_scenario(source).table.flexible, tmp_path)
    assert keys == {"modes": "top-modes.csv", "count": 2, "damping": 0.01, "origin": [0.0, 0.0, 0.0]}
    assert flexible_toml(load_scenario(source).table.flexible, tmp_path / "elsewhere")["modes"] == str(modes.resolve())


def test_a_bending_top_built_in_python(tmp_path, modes, monkeypatch):
    monkeypatch.chdir(tmp_path)
    top = load_flexible("top-modes.csv", thickness=SIZE[2], count=2)
    assert top == load_flexible(modes, thickness=SIZE[2], count=2)  # equal by the data, not the name
    base = scenario_from_dict(base_dict())
    table = dataclasses.replace(base.table, flexible=top)
    scenario = validate_scenario(base.with_changes(table=table, points=(Point("tool", (0.0, 0.0, 0.4),
                                                                              feet=[[0.1, 0.0], [-0.1, 0.0]]),)))
    assert scenario.points[0].feet == ((0.1, 0.0), (-0.1, 0.0))
    assert scenario.modal_data.n_modes == 2
    heavy = dataclasses.replace(table, mass=3000.0, inertia=(100.0, 100.0, 150.0))
    with pytest.raises(ScenarioError, match=r"\[table\] mass is 3000 kg"):
        validate_scenario(base.with_changes(table=heavy))
    with pytest.raises(ParameterError, match=r"count: must be a whole number >= 1, got 0"):
        load_flexible(modes, count=0)
    with pytest.raises(ParameterError, match=r"damping: must be < 1, got 1"):
        load_flexible(modes, damping=1.0)
    with pytest.raises(ParameterError, match=r"FlexibleTop.damping: must be in \[0, 1\), got 2"):
        FlexibleTop(modes="x", data=top.data, damping=2.0)
    with pytest.raises(ParameterError, match=r"Point.feet: must be a number"):
        Point("tool", (0.0, 0.0, 0.4), feet=[["a", 0.0]])
    with pytest.raises(ScenarioError, match=r"points\[0\].feet: must be a non-empty list"):
        validate_scenario(base.with_changes(points=(Point("tool", (0.0, 0.0, 0.4), feet=()),)))
    with pytest.raises(ScenarioError, match=r"points\[0\].feet\[0\]: must be a list of 2 numbers, got 3"):
        validate_scenario(base.with_changes(points=(Point("tool", (0.0, 0.0, 0.4), feet=[(0.0, 0.1, 0.2)]),)))
