"""Exported controllers: the generated C (compiled here) equals DiscreteController.step; names, JSON, bad input."""

from __future__ import annotations

import ctypes
import json
import math

import control
import numpy as np
import pytest

from c_controllers import build, compare, needs_compiler
from controllers.feedback import DiscreteController, ScheduleEntry, from_statespace
from isolator import ParameterError


def random_design(rng, n, p, m):
    a = rng.normal(size=(n, n))
    if n:
        a *= 0.95 / max(abs(np.linalg.eigvals(a)))
    return a, rng.normal(size=(n, p)), rng.normal(size=(m, n)) * 10.0, rng.normal(size=(m, p)) * 1e3


@needs_compiler
@pytest.mark.parametrize(("n", "p", "m"), [(5, 3, 4), (0, 2, 3)])
def test_plain_c_equals_python(tmp_path, n, p, m):
    rng = np.random.default_rng(1)
    ctrl = DiscreteController(2000.0, [f"s{i}" for i in range(p)], [f"a{i}" for i in range(m)], ["stage"], "test",
                              *random_design(rng, n, p, m))
    dll = build(ctrl, tmp_path)
    ys = rng.normal(size=(400, p)) * 1e-6
    qs = rng.uniform(-1, 1, size=(400, 1))  # ignored
    compare(ctrl, dll, ys, qs)


def scheduled(rng, carriages=("x-stage", "y-stage"), positions=(-0.3, -0.1, 0.05, 0.4)):
    entries = [ScheduleEntry([0.7 * k, q], *random_design(rng, 4, 3, 2)) for k, q in enumerate(positions)]
    return DiscreteController(1000.0, ["g1", "g2", "g3"], ["f1", "f2"], list(carriages), "lqg", schedule=entries,
                              schedule_carriage=1, settings={"schedule": len(positions)}, delay=True)


@needs_compiler
def test_a_single_point_schedule_is_a_plain_controller(tmp_path):
    rng = np.random.default_rng(9)
    ctrl = scheduled(rng, positions=(0.2,))
    dll = build(ctrl, tmp_path)
    compare(ctrl, dll, rng.normal(size=(100, 3)), rng.uniform(-1, 1, (100, 2)))


@needs_compiler
def test_scheduled_c_equals_python_across_and_beyond_the_points(tmp_path):
    rng = np.random.default_rng(2)
    ctrl = scheduled(rng)
    dll = build(ctrl, tmp_path)
    steps = 600
    q1 = np.concatenate([rng.uniform(-0.8, 0.9, steps - 8), [-0.3, -0.1, 0.05, 0.4, -5.0, 5.0, math.nan, 0.0]])
    qs = np.column_stack([rng.uniform(-1, 1, steps), q1])  # carriage 0 does not schedule
    compare(ctrl, dll, rng.normal(size=(steps, 3)), qs)
    # interpolation as documented: linear between points, clamped outside, carriage 0 ignored
    a = ctrl.schedule
    mid = ctrl.matrices([9.0, (-0.1 + 0.05) / 2])
    for got, lo, hi in zip(mid, (a[1].A, a[1].B, a[1].C, a[1].D), (a[2].A, a[2].B, a[2].C, a[2].D), strict=True):
        np.testing.assert_allclose(got, (lo + hi) / 2, rtol=1e-14, atol=1e-14)
    np.testing.assert_array_equal(ctrl.matrices([0.0, -3.0])[2], a[0].C)
    np.testing.assert_array_equal(ctrl.matrices([0.0, 3.0])[3], a[-1].D)


@needs_compiler
def test_names_are_escaped_and_read_back(tmp_path):
    sensors = ["end */ of comment", 'a "quoted" name', "back\\slash\\", "new\nline", "geophone ü 北", "??/ trigraph"]
    actuators = ["/* opens", "tab\there", "percent %d ' apostrophe"]
    carriages = ["*/\"\\\n"]
    ctrl = DiscreteController(500, sensors, actuators, carriages, 'me*/th"od', *random_design(
        np.random.default_rng(3), 2, len(sensors), len(actuators)), settings={"note": "*/"})
    dll = build(ctrl, tmp_path)
    for key, names in (("sensor", sensors), ("actuator", actuators), ("carriage", carriages)):
        table = (ctypes.c_char_p * (len(names) + 1)).in_dll(dll, f"isolator_ctrl_{key}_names")
        assert [b.decode("utf-8") for b in table[: len(names)]] == names
        assert table[len(names)] is None
    text = (tmp_path / "controller.c").read_text() + (tmp_path / "controller.h").read_text()
    assert text.isascii()
    for name in [*sensors, *actuators[:2], *carriages]:  # each holds a byte that must be escaped
        assert name not in text
    assert '"percent %d \' apostrophe"' in text
    rng = np.random.default_rng(4)
    compare(ctrl, dll, rng.normal(size=(50, len(sensors))), np.zeros((50, 1)))


@needs_compiler
def test_reset_puts_the_state_at_rest(tmp_path):
    rng = np.random.default_rng(5)
    ctrl = scheduled(rng)
    dll = build(ctrl, tmp_path)
    cc = compare(ctrl, dll, rng.normal(size=(30, 3)), rng.uniform(-0.5, 0.5, (30, 2)))
    assert np.abs(cc.x).max() > 0
    dll.isolator_ctrl_reset(cc.state)
    assert set(cc.state.raw) == {0}
    assert not cc.step([0.0, 0.0, 0.0], [0.0, 0.1]).any()
    np.testing.assert_array_equal(ctrl.reset(), np.zeros(4))
    # after a reset the C follows Python from rest again
    compare(ctrl, dll, rng.normal(size=(20, 3)), rng.uniform(-0.5, 0.5, (20, 2)))


def test_json_round_trip(tmp_path):
    rng = np.random.default_rng(6)
    plain = DiscreteController(1234.5, ["s1", "s\\2"], ["a"], [], "skyhook", *random_design(rng, 3, 2, 1),
                               settings={"gain": 0.1, "bands": [1, 2]})
    for ctrl in (plain, scheduled(rng)):
        path = ctrl.to_json(tmp_path)
        assert path == tmp_path / "controller.json"
        data = json.loads(path.read_text())
        for key in ("sample_rate", "sensors", "actuators", "carriages", "method", "A", "B", "C", "D"):
            assert key in data
        back = DiscreteController.from_json(tmp_path)
        assert back.to_dict() == ctrl.to_dict()
        assert (back.sample_rate, back.sensors, back.actuators, back.carriages, back.method, back.delay,
                back.settings) == (ctrl.sample_rate, ctrl.sensors, ctrl.actuators, ctrl.carriages, ctrl.method,
                                   ctrl.delay, ctrl.settings)
        x1 = x2 = ctrl.reset()
        positions = rng.uniform(-1, 1, (20, len(ctrl.carriages)))  # one per carriage (none for the plain one)
        for y, q in zip(rng.normal(size=(20, 2 if ctrl is plain else 3)), positions, strict=True):
            (x1, u1), (x2, u2) = ctrl.step(x1, y, q), back.step(x2, y, q)
            np.testing.assert_array_equal(u1, u2)
    data = json.loads((tmp_path / "controller.json").read_text())
    assert [e["q"][1] for e in data["schedule"]] == [-0.3, -0.1, 0.05, 0.4]
    assert data["delay"] is True


def test_from_statespace_discretises_as_python_control():
    sys = control.ss([[0.0, 1.0], [-400.0, -4.0]], [[0.0, 0.0], [1.0, 2.0]], [[3.0, 0.5]], [[0.1, 0.0]])
    for method in ("tustin", "zoh"):
        ctrl = from_statespace(sys, 1000.0, ["v1", "v2"], ["f"], method="lqg", discretisation=method)
        ref = control.c2d(sys, 1e-3, method=method)
        for got, want in zip((ctrl.A, ctrl.B, ctrl.C, ctrl.D), (ref.A, ref.B, ref.C, ref.D), strict=True):
            np.testing.assert_array_equal(got, want)
        assert ctrl.settings["discretisation"] == method
    discrete = control.c2d(sys, 1e-3)
    np.testing.assert_array_equal(from_statespace(discrete, 1000.0, ["v1", "v2"], ["f"]).A, discrete.A)
    with pytest.raises(ParameterError, match=r"^system: sampled every"):
        from_statespace(discrete, 500.0, ["v1", "v2"], ["f"])
    with pytest.raises(ParameterError, match=r"^system: must have 2 inputs"):
        from_statespace(sys, 1000.0, ["v1", "v2"], ["f", "g"])
    with pytest.raises(ParameterError, match=r"^discretisation:"):
        from_statespace(sys, 1000.0, ["v1", "v2"], ["f"], discretisation="euler")
    with pytest.raises(ParameterError, match=r"^sample_rate:"):
        from_statespace(sys, 0.0, ["v1", "v2"], ["f"])


def _entries(positions, n=2):
    rng = np.random.default_rng(7)
    return [ScheduleEntry([q], *random_design(rng, n, 1, 1)) for q in positions]


def _good(n=2):
    return random_design(np.random.default_rng(8), n, 1, 1)


def _bad_matrix(index, value):
    mats = list(_good())
    mats[index] = value
    return {"A": mats[0], "B": mats[1], "C": mats[2], "D": mats[3]}


@pytest.mark.parametrize(("kwargs", "name"), [
    (_bad_matrix(0, np.zeros((2, 3))), "A"),
    (_bad_matrix(1, np.zeros((3, 1))), "B"),
    (_bad_matrix(2, np.zeros((1, 3))), "C"),
    (_bad_matrix(3, np.zeros((2, 1))), "D"),
    (_bad_matrix(0, [[1.0, math.nan], [0.0, 0.0]]), "A"),
    (_bad_matrix(1, [[math.inf], [0.0]]), "B"),
    (_bad_matrix(3, [[-math.inf]]), "D"),
    ({**_bad_matrix(3, [[1.0]]), "sample_rate": 0.0}, "sample_rate"),
    ({**_bad_matrix(3, [[1.0]]), "sample_rate": -100.0}, "sample_rate"),
    ({**_bad_matrix(3, [[1.0]]), "sample_rate": math.inf}, "sample_rate"),
    ({**_bad_matrix(3, [[1.0]]), "D": None}, "D"),
    ({"schedule": _entries([0.0, 0.2, 0.2])}, "schedule"),
    ({"schedule": _entries([0.0, 0.3, 0.1])}, "schedule"),
    ({"schedule": [*_entries([0.0]), ScheduleEntry([0.1, 0.2], *_good())]}, "schedule[1].q"),
    ({"schedule": [*_entries([0.0]), ScheduleEntry([0.1], *_good(3))]}, "schedule[1].A"),
    ({"schedule": [*_entries([0.0]), ScheduleEntry([0.1], *_bad_matrix(2, [[0.0, math.nan]]).values())]},
     "schedule[1].C"),
    ({"schedule": _entries([0.0, 0.1]), "schedule_carriage": 1}, "schedule_carriage"),
    ({"schedule": _entries([0.0, 0.1]), **_bad_matrix(3, [[1.0]])}, "A"),
    ({**_bad_matrix(3, [[1.0]]), "sensors": []}, "sensors"),
    ({**_bad_matrix(3, [[1.0]]), "settings": {"x": math.nan}}, "settings"),
])
def test_bad_inputs_name_the_argument(kwargs, name):
    args = {"sample_rate": 1000.0, "sensors": ["s"], "actuators": ["a"], "carriages": ["c"], **kwargs}
    with pytest.raises(ParameterError) as error:
        DiscreteController(**args)
    assert str(error.value).startswith(f"{name}:"), str(error.value)
