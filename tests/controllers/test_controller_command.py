"""``isolator controller``: the three files, the C equal to the data, and every refusal one line with nothing
written."""

from __future__ import annotations

import json
from importlib.resources import files

import numpy as np
import pytest

from c_controllers import build, compare, needs_compiler
from conftest import run_command
from isolator.simulation.discrete_controller import DiscreteController

SCENARIO = "paper-table-3-2-geophones"


@needs_compiler
@pytest.mark.parametrize(("method", "extra"), [("lqg", ["--schedule", "3"]), ("skyhook", ["--delay"])])
def test_writes_the_three_files_and_the_c_equals_the_json(tmp_path, capsys, method, extra) -> None:
    out = tmp_path / "ctl"
    status, text, err = run_command(["controller", SCENARIO, "--method", method, "--sample-rate", "2000",
                                     "--out", str(out), *extra], capsys)
    assert status == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["controller.c", "controller.h", "controller.json"]
    data = json.loads((out / "controller.json").read_text())
    for key in ("sample_rate", "sensors", "actuators", "carriages", "method", "A", "B", "C", "D", "robustness"):
        assert key in data
    assert data["sensors"][:2] == ["v-x1", "v-y1"]
    assert data["actuators"][:2] == ["x1", "y1"]
    assert data["carriages"] == ["x-stage", "y-stage"]
    assert data["robustness"]["stable"] is True
    ctrl = DiscreteController.from_json(out)
    if "--schedule" in extra:
        assert [e["q"][0] for e in data["schedule"]] == pytest.approx([-0.7, 0.0, 0.7])
    else:
        assert ctrl.delay
    assert "margin" in text
    # the exported C is the controller of the JSON, compiled here and stepped side by side
    dll = build(ctrl, out)
    rng = np.random.default_rng(3)
    ys = rng.normal(size=(50, len(ctrl.sensors))) * 1e-5
    qs = np.column_stack([np.linspace(-0.9, 0.9, 50), np.zeros(50)])
    compare(ctrl, dll, ys, qs)


def _refused(capsys, tmp_path, argv, match) -> None:
    out = tmp_path / "refused"
    status, _text, err = run_command(["controller", *argv, "--out", str(out)], capsys)
    assert status == 2
    assert len(err) == 1, err
    assert err[0].startswith("isolator: error: ")
    assert match in err[0]
    assert not out.exists()


def test_refusals(tmp_path, capsys) -> None:
    bad_sensor = tmp_path / "bad-sensor.toml"
    text = (files("isolator") / "data" / "scenarios" / f"{SCENARIO}.toml").read_text()
    bad_sensor.write_text(text.replace('quantity = "velocity"', 'quantity = "jerk"', 1))
    _refused(capsys, tmp_path, [str(bad_sensor), "--method", "lqg", "--sample-rate", "2000"], "quantity")
    _refused(capsys, tmp_path, ["paper-table-3-2-active", "--method", "lqg", "--sample-rate", "2000"],
             "sensors: the lqg design feeds back the scenario's [[sensors]], and it has none")
    _refused(capsys, tmp_path, [SCENARIO, "--method", "skyhook", "--sample-rate", "5"],
             "below twice the table's highest mode")
    _refused(capsys, tmp_path, [SCENARIO, "--method", "lqg", "--sample-rate", "2000", "--gain", "1e4"],
             "--gain: not a setting of --method lqg")
    _refused(capsys, tmp_path, [SCENARIO, "--method", "hinf", "--sample-rate", "2000", "--schedule", "3"],
             "H-infinity")
    _refused(capsys, tmp_path, [SCENARIO, "--method", "lqg", "--sample-rate", "2000", "--uncertainty",
                                "stiffness=+-20"], "--uncertainty")
    _refused(capsys, tmp_path, [SCENARIO, "--method", "lqg", "--sample-rate", "2000", "--uncertainty",
                                "stiffness=+-99.9%"], "tips the passive table")
    blocked = tmp_path / "file"
    blocked.write_text("")
    status, _, err = run_command(["controller", SCENARIO, "--method", "lqg", "--sample-rate", "2000", "--out",
                                  str(blocked)], capsys)
    assert status == 2
    assert "--out" in err[0]


def test_checks_over_a_calibrations_intervals(tmp_path, capsys) -> None:
    """--calibration-json: the check runs over the calibration's 95 % intervals (here wide ones, named as
    `isolator calibrate --json` names them) and records them in controller.json."""
    calibration = tmp_path / "calibration.json"
    calibration.write_text(json.dumps({"parameters": {
        "isolators[*].stiffness.z": {"initial": 570000.0, "value": 570000.0, "std": 30000.0,
                                     "ci95": [510000.0, 630000.0]},
        "isolators[*].damping.z": {"initial": 5700.0, "value": 5700.0, "std": 900.0, "ci95": [3900.0, 7500.0]}},
        "identifiable": True}))
    out = tmp_path / "ctl"
    status, _, err = run_command(["controller", SCENARIO, "--method", "skyhook", "--sample-rate", "2000",
                                  "--out", str(out), "--calibration-json", str(calibration), "--json"], capsys)
    assert status == 0, err
    robustness = json.loads((out / "controller.json").read_text())["robustness"]
    assert set(robustness["uncertainty"]["intervals"]) == {"isolators[*].stiffness.z", "isolators[*].damping.z"}
    checked = {tuple(sorted(c["parameters"].items())) for c in robustness["cases"]}
    assert (("isolators[*].damping.z", 3900.0), ("isolators[*].stiffness.z", 630000.0)) in checked
    _refused(capsys, tmp_path, [SCENARIO, "--method", "lqg", "--sample-rate", "2000", "--uncertainty",
                                "stiffness=+-20%", "--calibration-json", str(calibration)], "not both")
