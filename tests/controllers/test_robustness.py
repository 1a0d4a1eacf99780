"""Issue 24 item 3: an output-feedback controller checked over the carriages' travel and the isolators'
uncertainty (controllers.feedback.robustness), on the bundled paper-table-3-2-geophones (12 geophones
collocated with 12 actuators lagging at 200 Hz; isolators of 5700 N s/m damping on every axis)."""

from __future__ import annotations

import dataclasses
import json

import control
import numpy as np
import pytest

from controllers.feedback import (
    DiscreteController,
    ScheduleEntry,
    Uncertainty,
    check_robustness,
    parse_uncertainty,
    uncertainty_from_calibration,
)
from controllers.feedback.sensor_plant import sensor_plant
from isolator import ParameterError, Simulator, load_scenario
from isolator.analysis.linear import linearise
from isolator.errors import UnstableClosedLoopError, UnstableTableError

RATE = 1000.0
Z1 = 2  # actuator z1 (and geophone v-z1) at the isolator at x = +1 m, y = +0.5 m
END = {"x-stage": -0.7, "y-stage": -0.3}  # both carriages at the end of their travel away from z1
MIDDLE = {"x-stage": 0.0, "y-stage": 0.0}


@pytest.fixture(scope="module")
def scenario():
    return load_scenario("paper-table-3-2-geophones")


def static(scenario, d, delay=False, rate=RATE):
    """A static output feedback ``u = D y`` [N per m/s] from the geophones to the actuators."""
    d = np.asarray(d, dtype=float)
    return DiscreteController(rate, [s.name for s in scenario.sensors], [a.name for a in scenario.actuators],
                              [c.name for c in scenario.carriages], A=np.zeros((0, 0)), B=np.zeros((0, 12)),
                              C=np.zeros((12, 0)), D=d, delay=delay)


def single(gain):
    """Only the loop from geophone v-z1 to actuator z1 closed, ``u_z1 = gain * v_z1``."""
    d = np.zeros((12, 12))
    d[Z1, Z1] = gain
    return d


def spectral_radius(scenario, positions, d, delay=False):
    """The sampled loop's spectral radius by python-control's feedback (independent of the module)."""
    sys = sensor_plant(linearise(scenario, positions=positions)).discrete(RATE, delay)
    plant = control.ss(sys.A, sys.B[:, :12], sys.C, sys.D[:, :12], 1.0 / RATE)
    loop = control.feedback(plant, control.ss([], [], [], d, 1.0 / RATE), sign=1)
    return float(np.max(np.abs(loop.poles())))


def critical(scenario, positions, shape, lo, hi):
    """The gain factor on ``shape`` where the spectral radius reaches 1, by bisection (stable at ``lo``)."""
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if spectral_radius(scenario, positions, mid * shape) < 1.0 else (lo, mid)
    return 0.5 * (lo + hi)


def test_collocated_velocity_feedback_passes_everywhere_with_positive_margins(scenario):
    calls = []
    report = check_robustness(scenario, static(scenario, -2000.0 * np.eye(12)),
                              parse_uncertainty("stiffness=+-20%,damping=+-30%"),
                              progress=lambda done, total: calls.append((done, total)))
    assert len(report.cases) == 81
    assert calls[-1] == (81, 81)
    assert len(calls) == 81
    assert {c.positions for c in report.cases} == {(x, y) for x in (-0.7, 0.0, 0.7) for y in (-0.3, 0.0, 0.3)}
    assert {dict(c.values).get("stiffness", 1.0) for c in report.cases} == {0.8, 1.0, 1.2}
    assert report.stable
    report.raise_if_unstable()
    for case in report.cases:
        mg = case.margins
        assert case.spectral_radius < 1.0
        assert mg is not None
        assert np.all(mg.gain_margin > 1.0)
        assert np.all(mg.gain_margin_low < 1.0)
        assert np.all(mg.phase_margin > 0.0)
        assert np.all(mg.loop_disk_margin > 0.0)
        assert mg.disk_margin > 0.0
    data = json.loads(json.dumps(report.to_dict(), allow_nan=False))
    assert data["stable"]
    assert data["cases_checked"] == 81
    assert data["unstable_cases"] == 0
    assert data["worst"]["spectral_radius"] == max(c.spectral_radius for c in report.cases)
    assert set(data["worst"]["actuators"]) == {a.name for a in scenario.actuators}
    assert data["worst_disk_margin"]["disk_margin"] == pytest.approx(min(c.margin("disk_margin")
                                                                           for c in report.cases))
    lines = report.summary()
    assert "stable in 81 of 81 cases" in lines[0]
    assert any("disk margin" in line for line in lines)


def test_the_flipped_sign_is_refused_naming_where(scenario):
    """Positive velocity feedback takes damping away: c = 2000 N s/m per actuator leaves the isolators'
    5700 N s/m a positive remainder, so it is refused only where the damping may fall below 2000 N s/m
    (x0.3 of +-70 %); c = 8000 N s/m exceeds it everywhere."""
    flipped = static(scenario, 2000.0 * np.eye(12))
    assert check_robustness(scenario, flipped).stable
    with pytest.raises(UnstableClosedLoopError) as error:
        check_robustness(scenario, flipped, parse_uncertainty("damping=+-70%")).raise_if_unstable()
    message = str(error.value)
    assert "\n" not in message
    assert "damping x0.3" in message
    assert "x-stage at" in message
    assert "y-stage at" in message
    assert "spectral radius" in message
    report = check_robustness(scenario, static(scenario, 8000.0 * np.eye(12)))
    assert not any(c.stable for c in report.cases)
    assert all(c.margins is None for c in report.cases)
    with pytest.raises(UnstableClosedLoopError, match="9 of 9 cases unstable"):
        report.raise_if_unstable()
    assert json.dumps(report.to_dict(), allow_nan=False)


def test_a_design_stable_mid_travel_but_not_at_the_end_is_refused_naming_the_end(scenario):
    """Positive velocity feedback of 13000 N s/m on the one vertical loop at z1 (x = +1, y = +0.5 m): it
    pumps energy into every mode that moves that corner, against the damping of all four isolators.
    With the carriages in the middle the four corners share the mass evenly and the loop is stable
    (critical gain about 13460 N s/m); with both carriages at the far end (x = -0.7, y = -0.3 m) the mass
    centre moves away from z1, so the rocking modes move that corner more for their modal mass and the
    same gain removes more of their damping than the isolators supply (critical gain about 12330 N s/m)."""
    design = static(scenario, single(13000.0))
    assert check_robustness(scenario, design, positions=[MIDDLE]).stable
    report = check_robustness(scenario, design)
    assert not report.stable
    assert report.worst.positions == (-0.7, -0.3)
    with pytest.raises(UnstableClosedLoopError, match=r"with x-stage at -0\.7 m, y-stage at -0\.3 m, nominal"):
        report.raise_if_unstable()
    # a schedule over the x-stage, sound in the middle and destabilising at the ends of its travel
    names = [s.name for s in scenario.sensors], [a.name for a in scenario.actuators]
    good, bad = -2000.0 * np.eye(12), 8000.0 * np.eye(12)
    points = [ScheduleEntry((q, 0.0), np.zeros((0, 0)), np.zeros((0, 12)), np.zeros((12, 0)), d)
              for q, d in ((-0.7, bad), (-0.35, good), (0.35, good), (0.7, bad))]
    scheduled = DiscreteController(RATE, *names, ["x-stage", "y-stage"], schedule=points)
    report = check_robustness(scenario, scheduled)
    assert {c.positions[0] for c in report.cases if not c.stable} == {-0.7, 0.7}
    assert all(c.stable for c in report.cases if c.positions[0] == 0.0)


@pytest.mark.parametrize("gain", [5000.0, -5000.0])
def test_the_loop_at_a_time_gain_margin_is_the_critical_gain(scenario, gain):
    """One loop closed (z1): its gain margin is where the closed loop's spectral radius, computed by
    python-control's feedback, reaches 1 (bisection), to 1 %."""
    report = check_robustness(scenario, static(scenario, single(gain)), positions=[END])
    margin = report.cases[0].margins.gain_margin[Z1]
    assert np.isfinite(margin)
    assert margin > 1.0
    assert margin == pytest.approx(critical(scenario, END, single(gain), 1.0, 1.5 * margin), rel=0.01)
    assert report.cases[0].margins.gain_margin_low[Z1] == 0.0  # the open loop is stable: no lower limit


def test_the_phase_margin_is_where_the_loop_gain_crosses_one(scenario):
    """A single stiff velocity loop (5e4 N s/m at z1): its return crosses |l| = 1 twice; the phase margin is
    the smaller |arg l| of the two, found here on python-control's frequency response of that loop on a
    grid 50 times finer than the check's."""
    gain = -5.0e4
    mg = check_robustness(scenario, static(scenario, single(gain)), positions=[END]).cases[0].margins
    sys = sensor_plant(linearise(scenario, positions=END)).discrete(RATE, False)
    f = np.logspace(-2, np.log10(RATE / 2), 20000)
    ret = gain * control.ss(sys.A, sys.B[:, Z1], sys.C[Z1], sys.D[Z1, Z1], 1.0 / RATE)(
        np.exp(2j * np.pi * f / RATE))
    cross = np.flatnonzero(np.diff(np.sign(np.abs(ret) - 1.0)))
    assert len(cross) == 2
    assert mg.phase_margin[Z1] == pytest.approx(np.degrees(np.abs(np.angle(ret[cross]))).min(), abs=0.1)
    assert f[cross[np.argmin(np.abs(np.angle(ret[cross])))]] == pytest.approx(mg.phase_frequency[Z1], rel=1e-3)
    assert 0.0 < mg.phase_margin[Z1] < 180.0


def test_the_multiloop_disk_margin_against_python_control(scenario):
    """python-control's disk_margins (SLICOT's mu) on a fine grid about the reported peak: the margin
    reported is a lower bound of it and close to it."""
    d = 2000.0 * np.eye(12)
    case = check_robustness(scenario, static(scenario, d), positions=[END]).cases[0]
    sys = sensor_plant(linearise(scenario, positions=END)).discrete(RATE, False)
    loop = -(control.ss([], [], [], d, 1.0 / RATE) * control.ss(sys.A, sys.B[:, :12], sys.C, sys.D[:, :12],
                                                                1.0 / RATE))
    f = case.margins.disk_frequency * np.linspace(0.9, 1.1, 31)
    dm = control.disk_margins(loop, 2 * np.pi * f)[0]
    assert dm * (1 - 1e-6) <= case.margins.disk_margin * 1.03
    assert case.margins.disk_margin <= dm * (1 + 1e-6)
    assert case.margins.disk_margin < np.min(case.margins.loop_disk_margin) + 1e-9


def test_one_sample_of_delay_is_honoured(scenario):
    """Collocated velocity feedback of 5e5 N s/m per actuator: stable at 1 kHz with the commands applied at
    once (critical about 9.4e5), unstable with one sample of computation delay (critical about 3.1e5)."""
    d = -5.0e5 * np.eye(12)
    check_robustness(scenario, static(scenario, d)).raise_if_unstable()
    with pytest.raises(UnstableClosedLoopError, match="with one sample of delay"):
        check_robustness(scenario, static(scenario, d, delay=True)).raise_if_unstable()


@pytest.mark.parametrize(("text", "stiffness", "damping"), [
    ("stiffness=+-20%,damping=+-30%", 0.2, 0.3), ("stiffness=20%", 0.2, 0.0), (" damping = ±5 % ", 0.0, 0.05),
    ("damping=+/-100%,stiffness=+-0.5%", 0.005, 1.0)])
def test_the_uncertainty_parser(text, stiffness, damping):
    u = parse_uncertainty(text)
    assert (u.stiffness, u.damping) == pytest.approx((stiffness, damping))


@pytest.mark.parametrize(("text", "reason"), [
    ("", "empty"), ("stiffness", "not KEY"), ("stifness=+-20%", "did you mean 'stiffness'"),
    ("mass=+-2%", "unknown key"), ("stiffness=+-20", "percent sign"), ("stiffness=-20%", "percentage"),
    ("stiffness=+-100%", "below 100"), ("damping=+-120%", "at most 100 %"),
    ("stiffness=+-2%,stiffness=+-3%", "given twice")])
def test_bad_uncertainty_is_one_line_naming_the_option(text, reason):
    with pytest.raises(ParameterError) as error:
        parse_uncertainty(text)
    message = str(error.value)
    assert message.startswith("--uncertainty: ")
    assert reason in message
    assert "\n" not in message


def test_the_sampling_scheme():
    assert Uncertainty().samples() == [()]
    assert len(Uncertainty(stiffness=0.2, damping=0.3).samples()) == 9
    three = Uncertainty(stiffness=0.2, intervals={"a": (1.0, 2.0), "b": (3.0, 4.0)}).samples()
    assert len(three) == 9
    assert three[0] == ()
    assert ("a", 2.0) in three[-1]
    six = Uncertainty(0.1, 0.1, dict.fromkeys("abcd", (1.0, 2.0))).samples()
    assert len(six) == 1 + 12 + 2 + 16
    assert six == Uncertainty(0.1, 0.1, dict.fromkeys("abcd", (1.0, 2.0))).samples()
    assert (("a", 1.0),) in six
    assert all(1.0 <= dict(s).get("a", 1.0) <= 2.0 for s in six)
    with pytest.raises(ParameterError, match="stiffness"):
        Uncertainty(stiffness=1.0)
    with pytest.raises(ParameterError, match="low <= high"):
        Uncertainty(intervals={"a": (2.0, 1.0)})


CALIBRATION = {  # the layout of `isolator calibrate table-3-2 --json` (values rounded)
    "parameters": {
        "isolators[*].stiffness.z": {"initial": 570000.0, "value": 655548.5, "std": 24.97,
                                     "ci95": [655499.6, 655597.4]},
        "isolators[*].damping.z": {"initial": 5700.0, "value": 4560.5, "std": 0.72, "ci95": [4559.1, 4561.9]},
        "table.mass": {"initial": 400.0, "value": 400.0, "std": None, "ci95": [100.0, 1000.0]},
    },
    "identifiable": False, "unidentifiable": [["table.mass"]], "correlation": [[1.0]], "experiments": {},
    "modes": {}, "residual_variance": 1.0, "evaluations": 10,
}


def test_the_calibration_reader_and_a_check_over_its_intervals(scenario, tmp_path):
    path = tmp_path / "calibration.json"
    path.write_text(json.dumps(CALIBRATION))
    u = uncertainty_from_calibration(path)
    assert dict(u.intervals) == {"isolators[*].stiffness.z": (655499.6, 655597.4),
                                 "isolators[*].damping.z": (4559.1, 4561.9)}
    assert "table.mass" in uncertainty_from_calibration(path, unidentified=True).intervals
    report = check_robustness(scenario, static(scenario, -2000.0 * np.eye(12)), u, positions=[END])
    assert len(report.cases) == 9
    assert report.stable
    assert report.cases[-1].values == (("isolators[*].stiffness.z", 655597.4), ("isolators[*].damping.z", 4561.9))
    bad = Uncertainty(intervals={"isolators[*].stifness.z": (1.0, 2.0)})
    with pytest.raises(ParameterError, match="did you mean"):
        check_robustness(scenario, static(scenario, -2000.0 * np.eye(12)), bad, positions=[END])


@pytest.mark.parametrize(("content", "reason"), [
    (None, "cannot read"), ("{", "cannot read as JSON"), ("[]", "no 'parameters'"),
    ('{"parameters": {"a": {"value": 1, "std": 1}}}', "ci95"),
    ('{"parameters": {"a": {"value": 1, "std": 1, "ci95": [2, 1]}}}', "ci95"),
    ('{"parameters": {"a": {"value": 1, "std": null, "ci95": [1, 2]}}}', "no parameter the records fix")])
def test_a_bad_calibration_json_is_one_line_naming_the_file(tmp_path, content, reason):
    path = tmp_path / "bad.json"
    if content is not None:
        path.write_text(content)
    with pytest.raises(ParameterError) as error:
        uncertainty_from_calibration(path)
    assert str(path) in str(error.value)
    assert reason in str(error.value)
    assert "\n" not in str(error.value)


def test_an_uncertainty_that_tips_the_table_is_refused(scenario):
    """Isolators 99 % softer cannot hold the table's high mass centre upright: linearise finds no stable
    equilibrium there (checked directly), and the check says which value and where."""
    with pytest.raises(UnstableTableError):
        linearise(scenario, positions=END, parameters=Simulator(scenario).scaled_parameters(0.01, 1.0))
    with pytest.raises(ParameterError) as error:
        check_robustness(scenario, static(scenario, -2000.0 * np.eye(12)), parse_uncertainty("stiffness=+-99%"),
                         positions=[END])
    message = str(error.value)
    assert message.startswith("uncertainty: stiffness x0.01 tips the passive table with x-stage at -0.7 m")
    assert "\n" not in message


def test_a_controller_for_other_sensors_is_refused(scenario):
    other = DiscreteController(RATE, [f"s{i}" for i in range(12)], [a.name for a in scenario.actuators],
                               A=np.zeros((0, 0)), B=np.zeros((0, 12)), C=np.zeros((12, 0)), D=np.eye(12))
    with pytest.raises(ParameterError, match=r"controller\.sensors"):
        check_robustness(scenario, other)
    with pytest.raises(ParameterError, match="positions"):
        check_robustness(scenario, static(scenario, np.eye(12)), positions=[])


def test_a_pneumatic_table_s_held_air_is_not_an_instability(scenario):
    """The pneumatic table's leveling groups hold their air with the valves closed: poles at z = 1 that no
    actuator or sensor reaches (the spectral radius would be 1 + round-off with them). They are left out
    as check_stability leaves them out, and the margins skip the frequency 0."""
    pneumatic = dataclasses.replace(load_scenario("paper-table-3-2-pneumatic-active"), sensors=scenario.sensors,
                                    actuators=scenario.actuators)
    report = check_robustness(pneumatic, static(scenario, -2000.0 * np.eye(12)), positions=[MIDDLE])
    assert report.stable
    assert report.cases[0].spectral_radius < 0.999
    assert report.cases[0].margins.disk_margin > 1.0
