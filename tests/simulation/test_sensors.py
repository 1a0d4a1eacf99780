"""Sensors: the s:<sensor> columns against the MuJoCo check's own kinematics, the linear model's sensor outputs
against the calibration's second-order form, and every bad [[sensors]] key."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import table_data
from isolator import ScenarioError, linearise, scenario_from_dict, simulate
from isolator.calibration.floor_model import FloorModel
from isolator.model.parameters import ParameterLayout


def _scenario(duration: float = 9.0, rate: float = 500.0):
    data = table_data()
    data["simulation"] = {"duration": duration, "sample_rate": rate}
    data["sensors"] += [{"name": f"{q}-tilted", "on": "table", "position": [0.9, -0.4, 0.15],
                         "direction": [0.6, 0.0, 0.8], "quantity": q} for q in ("displacement", "velocity")]
    return scenario_from_dict(data)


@pytest.mark.slow
def test_sensor_columns_equal_the_mujoco_check():
    pytest.importorskip("mujoco")
    from isolator.validation.synthetic_records import move_record

    sc = _scenario()
    run = simulate(sc)
    ref = move_record(sc, 9.0, 500.0)
    for name, values in ref.channels.items():
        ours = run.sensor(name)
        scale = np.max(np.abs(values)) if np.max(np.abs(values)) > 0 else 1.0
        assert np.max(np.abs(ours - values)) < 2e-5 * scale, name
    assert np.all(run.sensor("f-x") == 0.0)  # a still floor


def test_sensor_signals_are_each_others_derivatives():
    sc = _scenario(9.0, 2000.0)
    run = simulate(sc)
    dt = run.t[1] - run.t[0]
    d, v = run.sensor("displacement-tilted"), run.sensor("velocity-tilted")
    away = np.ones(run.t.size, bool)  # the acceleration jumps where the profiles' do; one-sided differences at the ends
    away[:5] = away[-5:] = False
    for b in sc.breakpoints:
        away &= np.abs(run.t - b) > 5 * dt
    assert np.max(np.abs(np.gradient(d, dt) - v)[away]) < 1e-4 * np.max(np.abs(v))
    # the x accelerometer at a0 against the derivative of the velocity of the same point along x
    data = table_data()
    data["simulation"] = {"duration": 9.0, "sample_rate": 2000.0}
    data["sensors"] = [{"name": "vx", "on": "table", "position": [0.95, 0.45, 0.15], "direction": [1.0, 0, 0],
                        "quantity": "velocity"}, {"name": "ax", "on": "table", "position": [0.95, 0.45, 0.15],
                                                  "direction": [1.0, 0, 0], "quantity": "acceleration"}]
    r = simulate(scenario_from_dict(data))
    a, dv = r.sensor("ax"), np.gradient(r.sensor("vx"), dt)
    assert np.max(np.abs(a - dv)[away]) < 1e-3 * np.max(np.abs(a))


def test_csv_has_the_sensor_columns(tmp_path):
    run = simulate(_scenario(9.0, 100.0))
    header = run.to_csv(tmp_path / "r.csv").read_text().splitlines()[0].split(",")
    assert [h for h in header if h.startswith("s:")] == [f"s:{s}" for s in run.sensor_names]


def test_linear_sensor_outputs_equal_the_second_order_form():
    """Two derivations: python-control's state space (shifted states, (jw)^k) and the calibration's
    ``(-w^2 M + jw C + K) d = -(G0 + jw G1) g`` with the sensor rows."""
    sc = _scenario()
    lin = linearise(sc)
    table = tuple(s for s in sc.sensors if s.on == "table")
    f = np.linspace(0.3, 40.0, 120)
    ours = lin.sensor_response(f, ["ground:x", "ground:y", "ground:z"])[:, [sc.sensors.index(s) for s in table]]
    other = FloorModel(ParameterLayout.of(sc), sc.initial_positions(), table).response(
        ParameterLayout.of(sc).pack(sc), f).H
    assert np.max(np.abs(ours.transpose(1, 2, 0) - other)) < 1e-10 * np.max(np.abs(other))
    assert [o for o in lin.output_names if o.startswith("s:")] == [f"s:{s.name}" for s in sc.sensors]
    # a displacement output of the state space (no floor-velocity subtlety) equals sensor_response
    k = lin.output_names.index("s:displacement-tilted")
    h = lin.frequency_response(f, ["ground:z"])[:, k, 0]
    ref = lin.sensor_response(f, ["ground:z"])[:, len(sc.sensors) - 2, 0]
    assert np.allclose(h, ref, rtol=1e-9, atol=0)


@pytest.mark.parametrize(("change", "message"), [
    ({"quantity": "jerk"}, "sensors[0].quantity: must be one of"),
    ({"on": "wall"}, "sensors[0].on: must be"),
    ({"direction": [0.0, 0.0, 2.0]}, "sensors[0].direction: must be a unit vector"),
    ({"direction": [0.0, 0.0]}, "sensors[0].direction: must be a list of three numbers"),
    ({"name": "t"}, "sensors[0].name: 't' is the records' time column"),
    ({"name": ""}, "sensors[0].name: must be a non-empty name"),
    ({"noise": -1.0}, "sensors[0].noise"),
    ({"position": [0.0, float("nan"), 0.0]}, "sensors[0].position[1]"),
    ({"uff": {"node": 3, "direction": "+Q"}}, "sensors[0].uff.direction"),
    ({"uff": {"node": -3, "direction": "+Z"}}, "sensors[0].uff.node"),
    ({"quantiy": "velocity"}, "sensors[0].quantiy: unknown key"),
])
def test_bad_sensors_are_one_clear_error(change, message):
    data = table_data()
    data["sensors"] = [{"name": "s", "on": "table", "position": [0.0, 0.0, 0.15], "direction": [0.0, 0.0, 1.0],
                        "quantity": "velocity", **change}]
    if "quantiy" in change:
        del data["sensors"][0]["quantity"]
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(data)
    assert message in str(info.value)
    assert "\n" not in str(info.value)


def test_a_sensor_name_used_twice_is_named():
    data = table_data()
    data["sensors"].append(dict(data["sensors"][0]))
    with pytest.raises(ScenarioError, match=r"sensors\[12\].name: 'a0-x' is used twice"):
        scenario_from_dict(data)


def test_scenarios_built_in_python_check_their_sensors():
    from dataclasses import replace

    from isolator.scenario.sensors import Sensor
    from isolator.scenario.validation import validate_scenario

    sc = _scenario(9.0, 100.0)
    with pytest.raises(ScenarioError, match=r"sensor\.quantity: must be one of"):
        Sensor("s", "table", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "jerk")
    twice = replace(sc, sensors=(*sc.sensors, sc.sensors[0]))
    with pytest.raises(ScenarioError, match=r"sensors\[14\].name: 'a0-x' is used twice"):
        validate_scenario(twice)
