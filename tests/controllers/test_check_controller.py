"""``isolator check-controller`` and the sampled loop it closes (isolator.analysis.closed_loop) on a bending top.

The scenario is the geophones table with a synthetic bending top (tests/synthetic_top.py): a twist at
900 Hz and a first bending along x at 600 Hz, one z actuator and one z velocity sensor collocated at the edge
``(1, 0, -0.15)`` (on the twist's nodal line ``y = 0``: only the bending mode and the rigid body are seen
there), the isolators moved to the bending mode's nodal lines ``x = +-1/sqrt(3)`` (so that they do not
damp or stiffen it), no carriages, actuators without lag. A static velocity feedback ``u_k = -g y_{k-1}``
(one sample of delay) is then a loop whose closed form is known: the bending mode sampled with a zero-order
hold, plus the rigid body (at 600 Hz a free mass: the isolators' 3-6 Hz is far below).
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from isolator import load_scenario
from isolator.analysis.closed_loop import check_controller
from isolator.scenario.definitions import Scenario
from isolator.simulation.actuation import ForceHistory
from isolator.simulation.discrete_controller import DiscreteController
from tests.synthetic_top import with_synthetic_top

FS = 2000.0
F_BEND, ZETA = 600.0, 0.01
EDGE = (1.0, 0.0, -0.15)


def _single_mode_scenario() -> Scenario:
    sc = load_scenario("paper-table-3-2-geophones")
    node = 1.0 / math.sqrt(3.0)
    isolators = tuple(dataclasses.replace(i, position=(math.copysign(node, i.position[0]), *i.position[1:]))
                      for i in sc.isolators)
    actuator = dataclasses.replace(sc.actuators[2], name="z", position=EDGE, bandwidth=None, max_force=1e9)
    sensor = dataclasses.replace(sc.sensors[2], name="v", position=EDGE)
    sc = dataclasses.replace(sc, isolators=isolators, carriages=(), actuators=(actuator,), sensors=(sensor,),
                             simulation=dataclasses.replace(sc.simulation, duration=0.3, sample_rate=20_000.0))
    return with_synthetic_top(sc, frequencies=(900.0, F_BEND), zeta=ZETA)


SCENARIO = _single_mode_scenario()


def _velocity_feedback(gain: float) -> DiscreteController:
    return DiscreteController(FS, ("v",), ("z",), (), method="velocity", A=np.zeros((0, 0)), B=np.zeros((0, 1)),
                              C=np.zeros((1, 0)), D=np.array([[-gain]]), delay=True)


def _closed_form_polynomial(gain: float) -> np.ndarray:
    """Characteristic polynomial of ``1 + g z^-1 (G_b(z) + G_r(z)) = 0``.

    The bending mode (modal mass normalised on the 4400 kg box, shape ``sqrt(5) (1.5 x^2 - 0.5)`` at the
    edge ``x = 1``: ``phi^2 = 5 / M``) from a held force to the velocity:
    ``G_b(z) = (1 - z^-1) Z{phi^2 e^(-a t) sin(wd t) / wd} = (phi^2 / wd) (z - 1) r sin(wd T) / (z^2 - 2 r cos(wd T)
    z + r^2)`` with ``a = zeta w``, ``r = exp(-a T)``; the rigid body at the edge, a free mass of mobility
    ``1 / M + x^2 / I_y`` (``I_y = M (lx^2 + t^2) / 12``): ``G_r(z) = (1 / M + 1 / I_y) T / (z - 1)``.
    Multiplying by ``z (z - 1) den``: ``z (z - 1) den + g beta (z - 1)^2 + g m_r T den``.
    """
    mass = 4400.0
    inertia = mass * (2.0**2 + 0.3**2) / 12.0
    w = 2 * math.pi * F_BEND
    t = 1.0 / FS
    wd = w * math.sqrt(1 - ZETA**2)
    r = math.exp(-ZETA * w * t)
    beta = (5.0 / mass) * r * math.sin(wd * t) / wd
    den = np.array([1.0, -2 * r * math.cos(wd * t), r * r])
    poly = np.polymul([1.0, 0.0], np.polymul([1.0, -1.0], den))
    poly = np.polyadd(poly, gain * beta * np.array([1.0, -2.0, 1.0]))
    return np.polyadd(poly, gain * (1.0 / mass + 1.0 / inertia) * t * den)


def _critical(stable: Callable[[float], bool], lo: float = 1e4, hi: float = 1e6, steps: int = 30) -> float:
    for _ in range(steps):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return math.sqrt(lo * hi)


def test_the_delayed_velocity_feedback_becomes_unstable_at_the_closed_form_gain() -> None:
    closed = _critical(lambda g: np.max(np.abs(np.roots(_closed_form_polynomial(g)))) < 1.0, steps=60)
    found = _critical(lambda g: check_controller(SCENARIO, _velocity_feedback(g)).stable)
    # the bending mode alone (no rigid body) would put it 1.2 % higher: the check must see both
    assert found == pytest.approx(closed, rel=1e-3)
    roots = np.roots(_closed_form_polynomial(1.01 * closed))
    z = roots[np.argmax(np.abs(roots))]
    loop = check_controller(SCENARIO, _velocity_feedback(1.01 * closed))
    assert not loop.stable
    assert loop.spectral_radius == pytest.approx(abs(z), abs=2e-5)
    assert loop.frequency_hz == pytest.approx(abs(np.angle(z)) * FS / (2 * math.pi), rel=1e-3)
    assert loop.growing_mode()[0] == "bending x 1"
    assert loop.growing_mode()[1] == pytest.approx(F_BEND, rel=1e-3)
    assert "bending x 1" in loop.describe()
    assert f"{loop.frequency_hz:.4g} Hz" in loop.describe()


@settings(max_examples=6, deadline=None)
@given(st.floats(0.05, 0.9))
def test_below_the_critical_gain_the_loop_is_stable_above_it_not(fraction: float) -> None:
    closed = _critical(lambda g: np.max(np.abs(np.roots(_closed_form_polynomial(g)))) < 1.0, steps=60)
    assert check_controller(SCENARIO, _velocity_feedback(fraction * closed)).stable
    assert not check_controller(SCENARIO, _velocity_feedback(closed / fraction ** 0.25)).stable


def _envelope(t: np.ndarray, y: np.ndarray, f: float, window: float) -> tuple[np.ndarray, np.ndarray]:
    """Complex demodulation at ``f`` [Hz]: ``y e^(-j 2 pi f t)`` averaged over ``window`` s (whole periods),
    giving the oscillation's complex amplitude over time (other frequencies average out)."""
    n = max(1, round(window / (t[1] - t[0])))
    kernel = np.ones(n) / n
    return np.convolve(t, kernel, mode="valid"), np.convolve(y * np.exp(-2j * math.pi * f * t), kernel, mode="valid")


def test_the_largest_eigenvalue_is_the_growth_and_frequency_of_a_time_domain_run() -> None:
    from isolator.simulation.simulator import Simulator

    controller = _velocity_feedback(1.5e5)
    loop = check_controller(SCENARIO, controller)
    rate = FS * math.log(loop.spectral_radius)  # growth [1/s]
    assert 20.0 < rate < 50.0
    kick = ForceHistory(np.array([0.0, 0.01, 0.01, 0.0105, 0.0105, 0.3]), np.array([[0, 0, 100, 100, 0, 0]]),
                        ("z",))
    response = Simulator(SCENARIO).run(forces=kick, controller=controller)
    t = response.t
    y = response.sensor("v")
    late = (t >= 0.1) & (t <= 0.3)
    ts, amp = _envelope(t[late], y[late], loop.frequency_hz, 10.0 / loop.frequency_hz)
    slope, _ = np.polyfit(ts, np.log(np.abs(amp)), 1)
    assert slope == pytest.approx(rate, rel=1e-3)
    # the frequency: the demodulated phase's drift is the difference from the check's frequency
    drift = np.polyfit(ts, np.unwrap(np.angle(amp)), 1)[0] / (2 * math.pi)
    assert abs(drift) < 0.05  # Hz, of 603 Hz


# --- the command line: the geophones table on the bundled top's six elastic modes --------------------------

GEOPHONES = Path(__file__).parents[2] / "isolator" / "data" / "scenarios"


def _replace_once(text: str, old: str, new: str) -> str:
    assert text.count(old) == 1, old
    return text.replace(old, new)


def _geophones_toml(folder: Path, bending: bool) -> Path:
    """The bundled geophones table (rigid, or on the bundled top's lowest six elastic modes), a short move of
    both carriages, a 0.45 s run sampled at 8 kHz, actuators that do not clip (a growing oscillation stays
    linear)."""
    text = (GEOPHONES / "paper-table-3-2-geophones.toml").read_text()
    text = _replace_once(text, 'stroke = 1.4, velocity = 0.2, acceleration = 0.5, t0 = 0.5',
                         'stroke = 0.005, velocity = 0.2, acceleration = 0.5, t0 = 0.02')
    text = _replace_once(text, 'stroke = 0.6, velocity = 0.083, acceleration = 0.5, t0 = 0.5',
                         'stroke = 0.002, velocity = 0.083, acceleration = 0.5, t0 = 0.02')
    text = re.sub(r"^duration = .*$", "duration = 0.45", text, count=1, flags=re.M)
    text = re.sub(r"^sample_rate = .*$", "sample_rate = 8000.0", text, count=1, flags=re.M)
    text = text.replace("max_force = 500.0", "max_force = 1.0e9")
    if bending:
        modes = (GEOPHONES / "paper-table-3-2-top-modes.csv").as_posix()
        text = text.replace("\n[[isolators]]", f'\n[table.flexible]\nmodes = "{modes}"\ncount = 6\ndamping = 0.01\n'
                            "\n[[isolators]]", 1)  # the table's last key, before the first isolator
    path = folder / f"geophones-{'bending' if bending else 'rigid'}.toml"
    path.write_text(text)
    return path


def _static_velocity_feedback(folder: Path, gain: float) -> Path:
    """``u = -gain y`` on every collocated geophone and actuator pair, with one sample of delay."""
    sc = load_scenario("paper-table-3-2-geophones")
    n = len(sc.sensors)
    controller = DiscreteController(FS, tuple(s.name for s in sc.sensors), tuple(a.name for a in sc.actuators),
                                    tuple(c.name for c in sc.carriages), method="velocity", A=np.zeros((0, 0)),
                                    B=np.zeros((0, n)), C=np.zeros((n, 0)), D=-gain * np.eye(n), delay=True)
    folder.mkdir(parents=True, exist_ok=True)
    controller.to_json(folder)
    return folder


def _cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    from isolator.cli.app import main

    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def test_a_loop_stable_on_the_rigid_top_and_not_on_the_bending_one_is_refused_by_simulate(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rigid, bending = _geophones_toml(tmp_path, False), _geophones_toml(tmp_path, True)
    ctl = str(_static_velocity_feedback(tmp_path / "ctl", 6e4))
    status, out, _ = _cli(capsys, "check-controller", ctl, str(rigid), "--json")
    assert status == 0
    assert json.loads(out)["stable"]
    assert json.loads(out)["disk_margin"] > 0
    status, out, _ = _cli(capsys, "check-controller", ctl, str(bending), "--json")
    report = json.loads(out)
    assert status == 3
    assert not report["stable"]
    assert report["disk_margin"] is None
    assert report["spectral_radius"] > 1.0
    f, radius, mode = report["frequency_hz"], report["spectral_radius"], report["mode"]
    assert mode == "plate 1"
    assert 400 < f < 480
    assert report["mode_frequency_hz"] == pytest.approx(f, rel=0.02)
    status, line, _ = _cli(capsys, "check-controller", ctl, str(bending))
    assert status == 3
    assert line.count("\n") == 1
    assert f"{f:.4g} Hz" in line
    assert "'plate 1'" in line

    csv = tmp_path / "run.csv"
    status, out, err = _cli(capsys, "simulate", str(bending), "--controller", ctl, "--json", "--out", str(csv))
    assert status == 3
    assert not csv.exists()
    assert err.count("\n") == 1
    assert err.startswith("isolator: error: --controller:")
    assert line.strip() in err
    assert "--allow-unstable" in err

    status, out, err = _cli(capsys, "simulate", str(bending), "--controller", ctl, "--allow-unstable", "--json",
                            "--out", str(csv))
    assert status == 0, err
    names = csv.read_text().splitlines()[0].split(",")
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    t, y = data[:, 0], data[:, names.index("s:v-z1")]
    late = t >= 0.2
    ts, amp = _envelope(t[late], y[late], f, 10.0 / f)
    slope = np.polyfit(ts, np.log(np.abs(amp)), 1)[0]
    drift = np.polyfit(ts, np.unwrap(np.angle(amp)), 1)[0] / (2 * math.pi)
    assert slope == pytest.approx(FS * math.log(radius), rel=0.01)  # it grows at the check's rate ...
    assert abs(drift) < 0.5  # Hz: ... at the check's frequency (441 Hz)


@pytest.mark.parametrize(("case", "expected"), [
    ("renamed", "controller.sensors[1]: 'v-y1' where the scenario's [[sensors]] has 'v-y1b'"),
    ("missing", "controller.json: cannot read"),
    ("travel", "--position.x-stage: 0.9 m is beyond the carriage's travel"),
    ("unknown", "x-stag"),
])
def test_bad_input_is_one_line_naming_it_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str,
                                                expected: str) -> None:
    ctl = str(_static_velocity_feedback(tmp_path / "ctl", 1e4))
    scenario = "paper-table-3-2-geophones"
    extra: list[str] = []
    if case == "renamed":
        text = (GEOPHONES / "paper-table-3-2-geophones.toml").read_text()
        path = tmp_path / "renamed.toml"
        path.write_text(_replace_once(text, 'name = "v-y1"', 'name = "v-y1b"'))
        scenario = str(path)
    elif case == "missing":
        ctl = str(tmp_path)
    else:
        extra = ["--position", "x-stage=0.9" if case == "travel" else "x-stag=0.1"]
    for argv in (["check-controller", ctl, scenario, *extra], ["check-controller", ctl, scenario, "--json", *extra]):
        status, out, err = _cli(capsys, *argv)
        assert status == 2
        assert not out
        assert err.count("\n") == 1, err
        assert err.startswith("isolator: error:"), err
        assert expected in err, err
    if case in ("renamed", "missing"):
        status, out, err = _cli(capsys, "simulate", scenario, "--controller", ctl, "--json")
        assert status == 2
        assert err.count("\n") == 1, err
        assert expected.replace("controller.json", "") in err, err


def test_allow_unstable_needs_a_controller(capsys: pytest.CaptureFixture[str]) -> None:
    status, _, err = _cli(capsys, "simulate", "paper-table-3-2-geophones", "--allow-unstable", "--json")
    assert status == 2
    assert err.count("\n") == 1
    assert "--allow-unstable" in err
    assert "--controller" in err


def test_the_check_is_the_robustness_checks_loop() -> None:
    """The designs' robustness check and the command give the same spectral radius and disk margin."""
    from controllers.check_command import loop_report
    from controllers.feedback.robustness import check_robustness

    sc = load_scenario("paper-table-3-2-geophones")
    n = len(sc.sensors)
    controller = DiscreteController(FS, tuple(s.name for s in sc.sensors), tuple(a.name for a in sc.actuators),
                                    tuple(c.name for c in sc.carriages), A=np.zeros((0, 0)), B=np.zeros((0, n)),
                                    C=np.zeros((n, 0)), D=-2e4 * np.eye(n), delay=True)
    q = {"x-stage": 0.3, "y-stage": 0.1}
    case = check_robustness(sc, controller, positions=[q]).cases[0]
    report = loop_report(check_controller(sc, controller, q), tuple(a.name for a in sc.actuators))
    assert report["spectral_radius"] == case.spectral_radius
    assert report["disk_margin"] == case.margins.disk_margin  # type: ignore[union-attr]
    assert report["positions"] == q


@settings(max_examples=4, deadline=None)
@given(st.floats(-0.7, 0.7))
def test_a_scheduled_controller_is_checked_at_the_positions_given(x: float) -> None:
    from controllers.feedback.output_feedback import design_controller
    from controllers.feedback.robustness import check_robustness

    sc = load_scenario("paper-table-3-2-geophones")
    if not _SCHEDULED:  # one design for every example
        _SCHEDULED.append(design_controller(sc, "lqg", 2000.0, schedule=3, options={"max_velocity": 0.01},
                                            search=False))
    controller = _SCHEDULED[0]
    assert len(controller.schedule) == 3
    loop = check_controller(sc, controller, {"x-stage": x})
    q = np.array([x, sc.carriages[1].profile.position(0.0)])
    for got, expected in zip(loop.controller, controller.matrices(q), strict=True):
        assert np.array_equal(got, expected)
    case = check_robustness(sc, controller, positions=[{"x-stage": x}], margins=False).cases[0]
    assert loop.spectral_radius == case.spectral_radius


_SCHEDULED: list[DiscreteController] = []


def test_the_budget_refuses_the_unstable_loop_with_the_checks_line(tmp_path: Path) -> None:
    from isolator.analysis.budget import error_budget
    from isolator.errors import UnstableClosedLoopError

    bending = load_scenario(_geophones_toml(tmp_path, True))
    controller = DiscreteController.from_json(_static_velocity_feedback(tmp_path / "ctl", 6e4) / "controller.json")
    line = check_controller(bending, controller).describe()
    with pytest.raises(UnstableClosedLoopError) as error:
        error_budget(bending, controller)
    assert line in str(error.value)
    assert "'plate 1'" in str(error.value)
