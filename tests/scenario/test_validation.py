"""Bad input gets one clear error naming the key path and the reason."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import pytest

from conftest import base_dict, make
from isolator import ScenarioError, load_scenario
from isolator.cli.app import main


def _with(path: str, value):
    data = base_dict()
    node = data
    keys = path.replace("]", "").replace("[", ".").split(".")
    for k in keys[:-1]:
        node = node[int(k)] if k.isdigit() else node[k]
    last = keys[-1]
    if value is _DELETE:
        del node[last]
    else:
        node[int(last) if last.isdigit() else last] = value
    return data


_DELETE = object()


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        ("table.mass", -1.0, "table.mass: must be > 0"),
        ("table.mass", 0.0, "table.mass: must be > 0"),
        ("table.mass", math.nan, "table.mass: must be finite"),
        ("table.size", [2.0, 1.0], "table.size: must be a list of three numbers"),
        ("table.colour", "grey", "table.colour: unknown key"),
        ("isolators[1].stiffness", [1e5, -1.0, 1e5], "isolators[1].stiffness[1]: must be >= 0"),
        ("isolators[2].damping", [1.0, math.inf, 1.0], "isolators[2].damping[1]: must be finite"),
        ("isolators[0].position", [1.0, "a", 0.0], "isolators[0].position[1]: must be a number"),
        ("carriages[0].mass", 0.0, "carriages[0].mass: must be > 0"),
        ("carriages[0].axis", [0.0, 0.0, 0.0], "carriages[0].axis: must be a unit vector, got zero length"),
        ("carriages[0].axis", [1.0, 1.0, 0.0], "carriages[0].axis: must be a unit vector, got length 1.414"),
        ("carriages[0].parent", "gantry", "carriages[0].parent: unknown parent 'gantry'"),
        ("carriages[0].parent", "x-stage", "carriages[0].parent: a carriage cannot be its own parent"),
        ("carriages[0].profile.acceleration", 0.0, "carriages[0].profile.acceleration: must be > 0"),
        ("carriages[0].profile.jerk", -5.0, "carriages[0].profile.jerk: must be > 0"),
        ("carriages[0].profile.type", "spline", "carriages[0].profile.type: unknown profile type"),
        ("carriages[0].profile.speed", 1.0, "carriages[0].profile.speed: unknown key"),
        ("carriages[0].profile.stroke", _DELETE, "carriages[0].profile.stroke: missing"),
        ("carriages[0].profile.stroke", 2.0, "carriages[0].profile: the carriage's mass reaches x = 1.6"),
        ("simulation.duration", 0.0, "simulation.duration: must be > 0"),
        ("simulation.sample_rate", math.inf, "simulation.sample_rate: must be finite"),
        ("gravity", -9.81, "gravity: must be >= 0"),
        ("settling", {"fraction": 1.5}, "settling.fraction: must be < 1"),
        ("settling", {"fraction": 0.05, "tolerance": [1e-6, 1e-6]}, "settling: give fraction or tolerance"),
        ("frobnicate", 1, "frobnicate: unknown key"),
    ],
)
def test_bad_values_are_named(path, value, message):
    with pytest.raises(ScenarioError) as err:
        make(_with(path, value))
    assert str(err.value).startswith(message), str(err.value)


def test_too_few_and_collinear_isolators():
    data = base_dict()
    data["isolators"] = data["isolators"][:2]
    with pytest.raises(ScenarioError, match=r"^isolators: need at least three, got 2"):
        make(data)
    data = base_dict()
    for i, iso in enumerate(data["isolators"]):
        iso["position"] = [0.5 * i, 0.0, -0.15]
    with pytest.raises(ScenarioError, match=r"^isolators: positions all lie on one line"):
        make(data)


def test_cyclic_and_duplicate_carriages():
    data = base_dict()
    a = copy.deepcopy(data["carriages"][0])
    b = copy.deepcopy(a)
    a.update(name="a", parent="b", origin=[0, 0, 0.1])
    b.update(name="b", parent="a", origin=[0, 0, 0.1])
    data["carriages"] = [a, b]
    with pytest.raises(ScenarioError, match=r"^carriages\[0\]\.parent: cyclic parents \(a -> b -> a\)"):
        make(data)
    data["carriages"] = [copy.deepcopy(base_dict()["carriages"][0])] * 2
    with pytest.raises(ScenarioError, match=r"^carriages\[1\]\.name: 'x-stage' is used twice"):
        make(data)


def test_samples_profile_errors(tmp_path: Path):
    data = base_dict()
    data["carriages"][0]["profile"] = {"type": "samples", "t": [0.0, 1.0, 0.5], "q": [0, 0.1, 0.2]}
    with pytest.raises(ScenarioError, match=r"profile\.t: sample times must be strictly increasing"):
        make(data)
    data["carriages"][0]["profile"] = {"type": "samples", "file": "missing.csv"}
    with pytest.raises(ScenarioError, match=r"^carriages\[0\]\.profile\.file: cannot read"):
        make(data)
    (tmp_path / "bad.csv").write_text("t,q\n0,0\n1,nan\n")
    data["carriages"][0]["profile"] = {"type": "samples", "file": "bad.csv"}
    from isolator import scenario_from_dict

    with pytest.raises(ScenarioError, match=r"profile\.file: '.*bad\.csv' line 3, column 'q': nan is not a finite"):
        scenario_from_dict(data, base_dir=tmp_path)


def test_samples_profile_from_csv(tmp_path: Path):
    (tmp_path / "move.csv").write_text("t,q\n0.2,-0.1\n0.8,0.0\n1.5,0.2\n")
    data = base_dict()
    data["carriages"][0]["profile"] = {"type": "samples", "file": "move.csv"}
    from isolator import scenario_from_dict

    sc = scenario_from_dict(data, base_dir=tmp_path)
    assert sc.stop_time == pytest.approx(1.5)
    assert sc.final_positions()[0] == pytest.approx(0.2)


def test_toml_errors_are_one_line(tmp_path: Path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\n[table]\nmass = -3\nsize = [1, 1, 1]\n')
    with pytest.raises(ScenarioError, match=r"table\.mass: must be > 0"):
        load_scenario(bad)
    assert main(["simulate", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["isolator: error: table.mass: must be > 0, got -3"]
    broken = tmp_path / "broken.toml"
    broken.write_text("name = \n")
    assert main(["simulate", str(broken)]) == 2
    assert "not valid TOML" in capsys.readouterr().err


def test_bundled_scenarios_load():
    for name in ("paper-table-3-1", "paper-table-3-2"):
        sc = load_scenario(name)
        assert sc.table.mass == 4400.0
        assert len(sc.isolators) == 4


def test_positions_in_mm_are_refused_naming_the_key_and_the_table():
    """Isolator positions in mm (600 m from a 2 m table) named at their key, not as an isolator 'far beyond a
    real one's' stiffness."""
    data = base_dict()
    for iso in data["isolators"]:
        iso["position"] = [1000 * v for v in iso["position"]]
    with pytest.raises(ScenarioError) as err:
        make(data)
    text = str(err.value)
    assert text.startswith("isolators[0].position: [1000, 500, -150] m lies"), text
    assert "+-1 m from the mass centre (table.size = [2, 1, 0.3] m), with 4 m for parts under a frame" in text
    assert "in mm?" in text


@pytest.mark.parametrize(("section", "key"), [("points", "position"), ("actuators", "position"),
                                              ("sensors", "position"), ("carriages", "origin")])
def test_every_table_position_is_checked_against_the_size(section, key):
    from conftest import active_dict

    data = active_dict()
    data["points"] = [{"name": "tool", "position": [0.0, 0.0, 0.5]}]
    data["sensors"] = [{"name": "floor", "on": "floor", "position": [50.0, 0.0, -3.0], "direction": [0, 0, 1.0],
                        "quantity": "velocity"},
                       {"name": "g", "on": "table", "position": [0.9, 0.4, 0.15], "direction": [0, 0, 1.0],
                        "quantity": "velocity"}]
    make(copy.deepcopy(data))  # a floor sensor is not on the table; the margin lets a tool point stand above it
    index = 1 if section == "sensors" else 0
    data[section][index][key] = [0.0, 0.0, 5.0]  # 4.85 m above a 0.3 m thick table: beyond the 4 m margin
    with pytest.raises(ScenarioError, match=rf"^{section}\[{index}\]\.{key}: \[0, 0, 5\] m lies 0\.85 m beyond"):
        make(data)


def test_a_frame_under_the_table_is_within_the_margin():
    data = base_dict()
    for iso in data["isolators"]:
        iso["position"] = [1.5 * iso["position"][0], 1.5 * iso["position"][1], -2.5]
    make(data)


def test_positions_in_mm_without_a_size_are_named_by_the_equilibrium():
    """Without table.size nothing bounds the positions; the failed rest names the isolator's lever, not a mass
    centre too high (the table would not tip)."""
    from isolator import Simulator, UnstableTableError

    data = base_dict()
    data["table"] = {"mass": 4400.0, "inertia": [400.0, 1500.0, 1800.0]}
    for iso in data["isolators"]:
        iso["position"] = [1000 * v for v in iso["position"]]
    with pytest.raises(UnstableTableError, match=r"would not tip .*isolators\[\d\]\.position lies 1\d{3} m from "
                                                 r"the table's mass centre \(positions in mm\?"):
        Simulator(make(data)).run()


def test_a_step_count_refusal_names_the_input_that_makes_the_mode_fast():
    from isolator.simulation.stepping import MAX_STEPS, check_step_count

    data = base_dict()
    data["isolators"][2]["stiffness"] = [1e5, 1e5, 1e13]
    scenario = make(data)
    omega = math.sqrt(1e13 / 4400.0) * 2
    with pytest.raises(ScenarioError, match=r"^isolators\[2\]\.stiffness: the table's fastest mode .* 1e\+13 N/m on a "
                                            r"table of 4800 kg"):
        check_step_count(omega, 10 * MAX_STEPS / omega, 1.0, scenario)
    with pytest.raises(ScenarioError, match=r"^isolators: .*far beyond a real isolator's"):
        check_step_count(omega * 1e3, 10 * MAX_STEPS / omega, 1.0, scenario)  # nothing that fast: no one named
