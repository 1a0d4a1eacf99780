"""Feedback controllers: designs against independent solutions, loops, sampling, saturation."""

from __future__ import annotations

import math

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import solve_continuous_are

from conftest import active_dict, make
from controllers import feedback as fb
from controllers.feedback.designs import actuated
from isolator import ParameterError, SimulationError, Simulator, UnstableClosedLoopError
from isolator.analysis.linear import FORCE_INPUTS, GROUND_INPUTS, linearise
from isolator.analysis.transmissibility import transmissibility
from isolator.scenario.definitions import SIGNALS


@pytest.fixture(scope="module")
def active():
    return make(active_dict())


@pytest.fixture(scope="module")
def lin(active):
    return linearise(active)


def test_lqr_gain_is_the_riccati_solution_and_python_controls(lin):
    a, b = actuated(lin)
    for scale in (1e-4, 1e-3):
        controller = fb.lqr(lin, scale, scale, 10 * scale, 10 * scale)
        gain = -np.asarray(controller.system.D)
        q = np.diag(np.r_[[scale**-2] * 6, [(10 * scale) ** -2] * 6])
        r = np.diag([1 / 500.0**2] * b.shape[1])
        riccati = solve_continuous_are(a, b, q, r)
        np.testing.assert_allclose(gain, np.linalg.solve(r, b.T @ riccati), rtol=1e-6, atol=1e-6 * np.abs(gain).max())
        if scale == 1e-3:  # well-conditioned enough for the unscaled solve
            reference, _, _ = control.lqr(a, b, q, r)
            np.testing.assert_allclose(gain, reference, rtol=1e-4, atol=1e-4 * np.abs(gain).max())
        assert np.all(np.linalg.eigvals(a - b @ gain).real < 0)


def test_skyhook_vertical_transmissibility_is_the_spring_damper_formula(active):
    lin0 = linearise(active, positions={"x-stage": 0.0})  # symmetric: z decouples
    c_sky = 3e4
    loop = fb.closed_loop(lin0, fb.skyhook(lin0, c_sky))
    f = np.logspace(-1, 2, 200)
    s = 2j * np.pi * f
    m = active.total_mass
    kk = sum(iso.stiffness[2] for iso in active.isolators)
    cc = sum(iso.damping[2] for iso in active.isolators)
    exact = (cc * s + kk) / (m * s**2 + (cc + 4 * c_sky) * s + kk)
    got = loop.frequency_response(f, ["ground:z"], ["z"])[:, 0, 0]
    np.testing.assert_allclose(got, exact, rtol=1e-9)
    # feedback changes the transmissibility: the peak drops below the passive one
    assert transmissibility(loop, f).peak("z")[0] < 0.6 * transmissibility(lin0, f).peak("z")[0]


def test_closed_loop_matches_python_controls_interconnection(lin):
    controller = fb.lead(lin, 1e5, 2.0, 20.0)
    loop = fb.closed_loop(lin, controller)
    sys = lin.system
    labels = list(sys.input_labels)
    measured = [f"m:{n}" for n in fb.MEASUREMENTS]
    plant = control.ss(sys.A, sys.B, np.vstack([np.asarray(sys.C)[:6], np.eye(12)]),
                       np.vstack([np.asarray(sys.D)[:6], lin.feedthrough]), inputs=labels,
                       outputs=[*SIGNALS, *measured], name="plant")
    k = controller.system
    ctrl = control.ss(k.A, k.B, k.C, k.D, inputs=measured, outputs=list(k.output_labels), name="ctrl")
    both = control.interconnect([plant, ctrl], inplist=[*GROUND_INPUTS, *FORCE_INPUTS], outlist=list(SIGNALS))
    f = np.logspace(-1, 2, 50)
    ref = np.moveaxis(both.frequency_response(2 * np.pi * f).complex, -1, 0)
    got = loop.frequency_response(f, [*GROUND_INPUTS, *FORCE_INPUTS], SIGNALS)
    np.testing.assert_allclose(got, ref, rtol=1e-7, atol=1e-9 * np.abs(ref).max())


def test_unstable_loops_are_detected_and_reported(active, lin):
    # collocated skyhook cannot destabilise the continuous loop, but sampling can
    hard = fb.skyhook(lin, 5e7)
    report = fb.check_stability(lin, hard)
    assert report.margin > 0
    assert report.spectral_radius > 1
    assert not report.stable
    with pytest.raises(UnstableClosedLoopError, match=r"unstable .* 1000 Hz sampling"):
        fb.feedback_law(active, hard)
    with pytest.raises(UnstableClosedLoopError):
        fb.closed_loop(lin, hard)
    # and the same loop run anyway, with actuators strong enough not to saturate, diverges and says so
    strong = make(active_dict(max_force=1e12))
    law = fb.feedback_law(strong, fb.skyhook(linearise(strong), 5e7), check=False)
    with pytest.raises(SimulationError, match="diverged"):
        Simulator(strong).run(feedback=law)
    # a faster sample rate makes it stable again
    assert fb.check_stability(lin, fb.skyhook(lin, 5e7, sample_rate=1e5)).stable


def test_sampled_loop_in_the_simulation_matches_an_independent_linear_loop():
    data = active_dict()
    start = data["carriages"][0]["profile"]["start"]
    data["carriages"][0]["profile"] = {"type": "samples", "t": [0.0, 0.5], "q": [start, start]}  # parked
    data["simulation"]["duration"] = 1.0
    motion = {"x": (2e-6, 9.0), "z": (3e-6, 21.0), "ry": (1e-6, 30.0)}
    data["ground"] = {axis: {"type": "sine", "amplitude": a, "omega": w} for axis, (a, w) in motion.items()}
    scenario = make(data)
    lin = linearise(scenario)
    controller = fb.lead(lin, 1e5, 2.0, 20.0, sample_rate=500.0)
    full = Simulator(scenario).run(feedback=fb.feedback_law(scenario, controller))
    # independent: python-control's Tustin, the linear plant integrated by DOP853 between ticks
    kd = control.c2d(controller.system, 1 / 500.0, method="tustin")
    a, b = np.asarray(lin.system.A), np.asarray(lin.system.B)
    labels = list(lin.system.input_labels)
    ig = [labels.index(n) for n in GROUND_INPUTS]
    ia = [labels.index(f"actuator:{act.name}") for act in scenario.actuators]
    b1 = lin.feedthrough[:, ig]

    def floor(t: float) -> np.ndarray:
        return scenario.ground.displacement(np.array([t]))[0, :6]

    xi, xc = np.zeros(12), np.zeros(kd.nstates)
    ticks = np.arange(0, 500) / 500.0
    out_t, out_y = [], []
    for t0 in ticks:
        m = xi + b1 @ floor(t0)
        u = np.asarray(kd.C) @ xc + np.asarray(kd.D) @ m
        xc = np.asarray(kd.A) @ xc + np.asarray(kd.B) @ m
        grid = full.t[(full.t >= t0 - 1e-12) & (full.t < t0 + 1 / 500.0 - 1e-12)]
        sol = solve_ivp(lambda t, x, u=u: a @ x + b[:, ig] @ floor(t) + b[:, ia] @ u, (t0, t0 + 1 / 500.0), xi,
                        t_eval=np.append(grid, t0 + 1 / 500.0), method="DOP853", rtol=1e-10, atol=1e-16)
        out_t.append(sol.t[:-1])
        out_y.append(sol.y[:6, :-1])
        xi = sol.y[:, -1]
    y = np.hstack(out_y)
    assert np.hstack(out_t).size == full.t.size - 1
    for k in (0, 2, 4):
        err = np.sqrt(np.mean((full.signals[k, :-1] - y[k]) ** 2)) / np.sqrt(np.mean(y[k] ** 2))
        assert err < 1e-4, (SIGNALS[k], err)
    # the feedback did something: the applied forces are not zero
    assert np.abs(full.actuator_forces).max() > 1e-3


def test_saturation_and_lag_hold_in_closed_loop():
    data = active_dict(max_force=20.0, bandwidth=50.0)
    data["simulation"]["duration"] = 6.0
    scenario = make(data)
    lin = linearise(scenario)
    law = fb.feedback_law(scenario, fb.skyhook(lin, 5e4))
    run = Simulator(scenario).run(feedback=law)
    assert np.abs(run.actuator_forces).max() <= 20.0 + 1e-9
    assert np.abs(run.actuator_forces).max() > 19.0  # the limit binds in this run
    passive = Simulator(scenario).run()
    assert run.settling_time_max < passive.settling_time_max


def test_controller_sample_rate_must_divide_the_simulation_rate(active, lin):
    law = fb.feedback_law(active, fb.skyhook(lin, 1e4, sample_rate=300.0))
    with pytest.raises(ParameterError, match=r"^feedback: the controller's sample rate 300 Hz must divide the "
                       r"scenario's simulation\.sample_rate"):
        Simulator(active).run(feedback=law)
    with pytest.raises(ParameterError, match="sample_rate: must be a rate > 0"):
        fb.skyhook(lin, 1e4, sample_rate=0.0)
    with pytest.raises(ParameterError, match="damping: must be a finite number > 0"):
        fb.skyhook(lin, -1.0)
    with pytest.raises(ParameterError, match="pole_hz: must be above zero_hz"):
        fb.lead(lin, 1e5, 20.0, 2.0)


def test_hinf_design_is_stable_and_quietens_the_table(lin):
    pytest.importorskip("slycot")
    controller = fb.hinf(lin)
    report = fb.check_stability(lin, controller)
    assert report.stable
    loop = fb.closed_loop(lin, controller)
    f = np.logspace(-1, 2, 300)
    passive = np.abs(lin.frequency_response(f, ["force:z"], ["z"]))[:, 0, 0].max()
    active = np.abs(loop.frequency_response(f, ["force:z"], ["z"]))[:, 0, 0].max()
    assert active < 0.5 * passive


def test_closed_loop_final_value_follows_the_controllers_dc_stiffness(active, lin):
    run_sky = Simulator(active).run(feedback=fb.feedback_law(active, fb.skyhook(lin, 2e4)))
    passive = Simulator(active).run()
    np.testing.assert_allclose(run_sky.final, passive.final, rtol=1e-12)  # no DC gain: same final value
    data = active_dict(max_force=1e6)  # strong enough to hold the tilt without saturating
    data["simulation"]["duration"] = 5.0
    strong = make(data)
    stiff = fb.feedback_law(strong, fb.pid(linearise(strong), kp=2e6))
    final = stiff.final(passive.final)
    ry = SIGNALS.index("ry")
    assert abs(final[ry]) < 0.6 * abs(passive.final[ry])  # stiffer table tilts less
    run = Simulator(strong).run(feedback=stiff)
    np.testing.assert_allclose(run.final, final, rtol=1e-12)
    assert math.isfinite(run.signals[ry, -1])
    assert abs(run.signals[ry, -1] - final[ry]) < 0.05 * abs(passive.final[ry])


def test_control_study_writes_figures_and_report(tmp_path, capsys):
    from isolator.cli.app import main

    assert main(["study", "control", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    for name in ("time.png", "transmissibility.png", "settling.png", "forces.png", "report.md"):
        assert (tmp_path / name).stat().st_size > 1000, name
    report = (tmp_path / "report.md").read_text()
    assert "| passive |" in report
    assert "| both |" in report
    settle = {line.split(":")[0].strip(): line for line in out.splitlines() if "settling" in line}
    assert "n/a" not in settle["feedback"]
    passive = float(settle["passive"].split("settling")[1].split()[0])
    feedback = float(settle["feedback"].split("settling")[1].split()[0])
    assert feedback < 0.2 * passive  # skyhook damps the ringing
    assert float(settle["both"].split("settling")[1].split()[0]) <= 0.020


def test_control_study_needs_actuators(tmp_path, capsys):
    from isolator.cli.app import main

    assert main(["study", "control", "paper-table-3-2", "--out", str(tmp_path)]) == 2
    assert "needs a scenario with [[actuators]]" in capsys.readouterr().err
