"""Trust round 4 (issue 42), item 6: a ``.`` in a point, actuator, sensor, disturbance, carriage or scenario name
(the name rule allows it) works in every analysis on python-control (which reads ``.`` as a subsystem's
signal), and every output shows the names as given."""

from __future__ import annotations

import json
import tomllib

from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from conftest import run_command
from controllers.feedback.output_feedback import design_controller
from isolator import error_budget, linearise, modes, scenario_from_dict, transmissibility
from isolator.analysis.signal_names import DOT, from_control, to_control
from isolator.scenario.bundled import bundled_scenarios
from isolator.scenario.names import FORMULA_STARTS

BUDGET = bundled_scenarios()["paper-table-3-2-budget"]
#: names by the rule, each with at least one dot
PART = st.text(st.characters(min_codepoint=33, max_codepoint=0x17F, blacklist_characters="."), min_size=1,
               max_size=6).filter(lambda s: s.isprintable() and s[0] not in FORMULA_STARTS)
DOTTED = st.lists(PART, min_size=2, max_size=3).map(".".join)


def _renamed(point: str, actuator: str, sensor: str, disturbance: str) -> dict:
    data = tomllib.loads(BUDGET.read_text())
    data["name"] = f"{point}.table"
    data["points"][0]["name"] = point
    data["actuators"][2]["name"] = actuator  # z1: a vertical actuator, with amplifier noise in the budget
    data["sensors"][0]["name"] = sensor
    data["disturbances"][0]["name"] = disturbance
    return data


@given(name=st.text(st.characters(min_codepoint=32, max_codepoint=0x2FF)).filter(str.isprintable))
def test_the_mapping_is_one_to_one_and_leaves_no_dot(name):
    assert "." not in to_control(name)
    assert from_control(to_control(name)) == name
    assert DOT not in name  # no printable name holds it


@given(point=DOTTED, actuator=DOTTED, sensor=DOTTED, disturbance=DOTTED)
@settings(max_examples=3, deadline=None, phases=[Phase.generate], suppress_health_check=[HealthCheck.too_slow])
def test_every_analysis_takes_dotted_names_and_shows_them_as_given(point, actuator, sensor, disturbance):
    scenario = scenario_from_dict(_renamed(point, actuator, sensor, disturbance), base_dir=BUDGET.parent)
    lin = linearise(scenario)
    assert f"actuator:{actuator}" in lin.input_names
    assert f"{point}:z" in lin.output_names
    assert f"s:{sensor}" in lin.output_names
    assert modes(lin).frequencies_hz.size == 6
    assert transmissibility(lin).magnitude("z").size > 0
    passive = error_budget(scenario)
    assert passive.points[0] == point
    assert f"force:{disturbance}" in passive.sources
    assert f"actuator:{actuator}" in passive.sources
    controller = design_controller(scenario, "skyhook", 2000.0, options={"gain": 2000.0, "highpass_hz": 0.5})
    assert controller.sensors[0] == sensor
    assert controller.actuators[2] == actuator
    closed = error_budget(scenario, controller)
    assert f"sensor:{sensor}" in closed.sources
    assert not any(DOT in name for name in (*closed.sources, *closed.points))


def test_the_commands_print_and_write_dotted_names_as_given(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    data = _renamed("probe.1", "act.x", "s.1", "acoustic.z")
    scenario = tmp_path / "dots.toml"
    import tomli_w

    scenario.write_text(tomli_w.dumps(data))
    for argv in (["modes"], ["transmissibility"]):
        status, out, err = run_command([*argv, str(scenario)], capsys)
        assert status == 0, err
    status, out, err = run_command(["controller", str(scenario), "--method", "skyhook", "--sample-rate", "2000",
                                    "--gain", "2000", "--highpass", "0.5", "--out", "ctl"], capsys)
    assert status == 0, err
    written = json.loads((tmp_path / "ctl" / "controller.json").read_text())
    assert written["sensors"][0] == "s.1"
    assert written["actuators"][2] == "act.x"
    status, out, err = run_command(["budget", str(scenario), "--controller", "ctl", "--out", "b.csv"], capsys)
    assert status == 0, err
    assert "probe.1:z:" in out
    header = (tmp_path / "b.csv").read_text().splitlines()[0]
    assert "probe.1:z:sensor:s.1" in header
    assert "probe.1:z:actuator:act.x" in header
