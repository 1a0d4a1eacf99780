"""Sensors on a top that bends read its elastic translation at their point: a velocity reading is the rate of
the displacement reading and an acceleration the rate of the velocity (the samples' central differences), the
compiled loop's readings equal the results' columns, and the linear model's sensor outputs include the modes."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
from synthetic_top import with_synthetic_top, without_top_modes

from isolator import Simulator, linearise
from isolator.model.cache import get_model
from isolator.model.parameters import ParameterLayout
from isolator.model.rotations import pose_rotation
from isolator.scenario.sensors import Sensor
from isolator.simulation.sampled_loop import readings
from isolator.simulation.sensors import sensor_signals
from isolator.simulation.time_grid import inputs_at

CORNER = (0.9, 0.4, 0.15)


def _scenario():
    base = with_synthetic_top(frequencies=(40.0, 60.0, 75.0))
    sensors = tuple(Sensor(f"s{k}", "table", CORNER, (0.0, 0.0, 1.0), q)
                    for k, q in enumerate(("displacement", "velocity", "acceleration")))
    return dataclasses.replace(base, sensors=sensors,
                               simulation=dataclasses.replace(base.simulation, duration=9.0, sample_rate=10000.0))


def test_a_reading_is_the_rate_of_the_one_below_it():
    scenario = _scenario()
    r = Simulator(scenario).run()
    s = r.sensor_signals
    dt = r.t[1] - r.t[0]
    # away from the profiles' acceleration jumps, where the acceleration itself jumps
    smooth = np.all(np.abs(r.t[1:-1, None] - np.array(scenario.breakpoints)[None, :]) > 3 * dt, axis=1)
    for low, high in ((0, 1), (1, 2)):
        rate = (s[low, 2:] - s[low, :-2]) / (2 * dt)
        scale = np.max(np.abs(s[high]))
        assert np.max(np.abs(rate - s[high, 1:-1])[smooth]) < 2e-3 * scale
    # the elastic part is there: the top's corner does not move as the rigid table's corner would
    rigid = Simulator(without_top_modes(scenario)).run()
    assert np.max(np.abs(s[2] - rigid.sensor_signals[2])) > 1e-2 * np.max(np.abs(s[2]))


def test_the_loops_readings_are_the_results_columns():
    scenario = _scenario()
    r = Simulator(scenario).run()
    model = get_model(ParameterLayout.of(scenario))
    p = ParameterLayout.of(scenario).pack(scenario)
    x, c, ps, ref = (ca.SX.sym(n, k) for n, k in (("x", model.n_states), ("c", model.layout.input_size),
                                                  ("p", model.layout.size), ("r", model.n_states)))
    fn = ca.Function("f", [x, c, ps, ref], [readings(model, scenario.sensors, x, c, ps, ref)])
    rows = slice(1000, 90000, 997)
    t = r.t[rows]
    c_now = inputs_at(scenario, t, t)
    got = np.asarray(fn(r.states[rows].T, c_now.T, p, r.states[0])).reshape(len(scenario.sensors), -1)
    want = sensor_signals(scenario, model, t, r.states[rows], c_now, p, r.states[0])
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12 * np.max(np.abs(want)))


def test_the_linear_models_sensors_see_the_modes():
    scenario = _scenario()
    lin = linearise(scenario)
    f = np.array([40.0, 60.0, 75.0])
    h = lin.sensor_response(f, ["force:z"])
    # the displacement sensor's response is its system output's, both with the top's elastic translation ...
    np.testing.assert_allclose(h[:, 0, 0], lin.frequency_response(f, ["force:z"], ["s:s0"])[:, 0, 0], rtol=1e-10)
    # ... which is the rigid motion at the corner plus the modal coordinates through the corner's shape
    shape = scenario.table.flexible.data.point_translation(CORNER, None, "s0")[:, 2]
    system = lin.system
    rot0 = pose_rotation(lin.equilibrium.pose[3:6])
    n = np.array([0.0, 0.0, 1.0])
    rigid_row = np.zeros(system.nstates)
    rigid_row[:3], rigid_row[3:6] = n, np.cross(rot0 @ CORNER, n)  # n . (dx + dphi x R0 r)
    rigid_row[6:9] = n @ rot0 @ scenario.table.flexible.data.point_translation(CORNER, None, "s0").T
    a, b = np.asarray(system.A), np.asarray(system.B)[:, [lin.input_names.index("force:z")]]
    states = np.linalg.solve(2j * np.pi * f[:, None, None] * np.eye(a.shape[0]) - a[None], b[None])[:, :, 0]
    np.testing.assert_allclose(states @ rigid_row, h[:, 0, 0], rtol=1e-9)
    assert np.max(np.abs(states[:, 6:9] @ shape)) > 1e-3 * np.max(np.abs(h[:, 0, 0]))
    rigid = linearise(without_top_modes(scenario))
    assert np.all(np.abs(rigid.sensor_response(f, ["force:z"])[:, 0, 0] - h[:, 0, 0]) > 0)
