"""Profile building blocks: S-curves with separate braking, shaping, shapers, move designs, limits."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import signal

from conftest import base_dict
from controllers.profiles import dominant_modes, move_designs, residual_vibration, shaper, time_optimal_profile
from isolator import ScenarioError, linearise, load_scenario, scenario_from_dict, scurve, shaped, trapezoid
from isolator.analysis.modes import modes


@pytest.mark.parametrize(("stroke", "dec", "jerk_down"), [(1.4, 0.3, 1.0), (-0.6, 0.2, 0.5), (0.02, 0.4, 2.0)])
def test_scurve_with_its_own_braking_is_continuous_within_limits_and_reaches_the_stroke(stroke, dec, jerk_down):
    p = scurve(start=0.1, stroke=stroke, velocity=0.2, acceleration=0.5, jerk=10.0, t0=0.3, deceleration=dec,
               deceleration_jerk=jerk_down)
    t = np.linspace(0.0, p.stop_time + 0.5, 200_001)
    q, v, a = p.evaluate(t)
    assert q[-1] == pytest.approx(0.1 + stroke, abs=1e-12)
    assert np.max(np.abs(v)) <= 0.2 + 1e-12
    s = math.copysign(1.0, stroke)
    assert np.max(s * a) <= 0.5 + 1e-9
    assert np.max(-s * a) <= dec + 1e-9
    dt = t[1] - t[0]
    assert np.max(np.abs(np.diff(a))) / dt <= max(10.0, jerk_down) * 1.001  # acceleration continuous
    assert np.allclose(np.diff(q) / dt, (v[1:] + v[:-1]) / 2, atol=1e-6)
    braking = t > p.knots[4]
    assert np.max(np.abs(np.diff(a[braking]))) / dt <= jerk_down * 1.001


def test_scurve_matches_ruckig_time_optimal_move():
    """ruckig, an independent solver, finds the same jerk-limited minimum-time move."""
    ours = scurve(start=-0.7, stroke=1.4, velocity=0.2, acceleration=0.5, jerk=10.0, t0=0.5)
    theirs = time_optimal_profile(-0.7, 1.4, 0.5, 0.2, 0.5, 10.0)
    assert theirs.stop_time == pytest.approx(ours.stop_time, abs=1e-9)
    t = np.linspace(0, 8.5, 5001)
    for mine, other in zip(ours.evaluate(t), theirs.evaluate(t), strict=True):
        assert np.allclose(mine, other, atol=1e-9)


def test_shaped_profile_is_the_sum_of_shifted_copies():
    base = trapezoid(start=0.0, stroke=0.5, velocity=0.2, acceleration=0.5, t0=0.2)
    amps, delays = [0.3, 0.5, 0.2], [0.0, 0.13, 0.31]
    p = shaped(base, amps, delays)
    t = np.random.default_rng(1).uniform(0, 4, 500)
    expected = sum(a * base.evaluate(t - d)[0] for a, d in zip(amps, delays, strict=True))
    assert np.allclose(p.evaluate(t)[0], expected, atol=1e-12)
    assert p.stop_time == pytest.approx(base.stop_time + 0.31)
    assert np.max(np.abs(p.evaluate(np.linspace(0, 4, 4001))[2])) <= 0.5 + 1e-12


@pytest.mark.parametrize("kind", ["zv", "zvd", "ei"])
def test_shaper_residual_vibration_matches_a_simulated_oscillator(kind):
    f, zeta = 3.4, 0.1
    train = shaper(kind, f, zeta)
    assert sum(train.amplitudes) == pytest.approx(1.0)
    w = 2 * math.pi * f
    osc = signal.lti([w * w], [1, 2 * zeta * w, w * w])
    t = np.linspace(0, 4, 40_001)

    sigma, wd = zeta * w, w * math.sqrt(1 - zeta**2)

    def ringing(amps, times):  # amplitude of the oscillation after a step fed through the impulse train
        u = sum(a * (t >= ti) for a, ti in zip(amps, times, strict=True))
        _, y, _ = signal.lsim(osc, u, t)
        r, dr = y - 1, np.gradient(y, t)
        k = np.searchsorted(t, times[-1] + 0.5)
        return math.hypot(r[k], (dr[k] + sigma * r[k]) / wd) * math.exp(sigma * t[k])

    # Singer and Seering's convention: against the unshaped step given at the last impulse's time
    measured = ringing(train.amplitudes, train.times) / ringing([1.0], [train.times[-1]])
    assert measured == pytest.approx(residual_vibration(train, f, zeta), abs=2e-3)
    expected = {"zv": 0.0, "zvd": 0.0, "ei": 0.05}[kind]
    assert residual_vibration(train, f, zeta) == pytest.approx(expected, abs=2e-3)
    if kind != "zv":  # the robust shapers stay low 10 % off the design frequency
        assert residual_vibration(train, 1.1 * f, zeta) < 0.06


def test_dominant_modes_are_the_tables_modes_and_the_x_move_rocks_x_and_z():
    sc = load_scenario()
    lin = linearise(sc, positions=sc.final_positions())
    freqs = sorted(modes(lin).frequencies_hz)
    ranked = dominant_modes(sc, 0)
    assert sorted(m.frequency for m in ranked) == pytest.approx(freqs, rel=1e-9)
    assert {round(m.frequency, 2) for m in ranked[:2]} == {3.36, 3.45}  # the x / z pair


def test_move_designs_describe_the_scenario_profiles():
    sc = load_scenario()
    for design, carriage in zip(move_designs(sc), sc.carriages, strict=True):
        assert design.stop_time() == pytest.approx(carriage.profile.stop_time, abs=1e-9)
        t = np.linspace(0, 9, 9001)
        assert np.allclose(design.profile().evaluate(t)[0], carriage.profile.evaluate(t)[0], atol=1e-12)
    for design in move_designs(sc, "scurve"):
        assert design.fits()
        assert sum(s.duration for s in design.segments()) == pytest.approx(design.profile().stop_time - design.t0)


def test_limits_are_read_and_checked():
    data = base_dict()
    data["carriages"][0]["limits"] = {"velocity": 0.5, "jerk": 20.0}
    sc = scenario_from_dict(data)
    assert sc.carriages[0].limits.jerk == 20.0
    assert sc.carriages[0].limits.acceleration is None
    assert move_designs(sc)[0].limits.jerk == 20.0
    data["carriages"][0]["limits"] = {"jerk": -1.0}
    with pytest.raises(ScenarioError, match=r"carriages\[0\]\.limits\.jerk: must be > 0"):
        scenario_from_dict(data)
    data["carriages"][0]["limits"] = {"snap": 1.0}
    with pytest.raises(ScenarioError, match=r"carriages\[0\]\.limits\.snap: unknown key"):
        scenario_from_dict(data)


def test_profile_design_refuses_a_sine():
    data = base_dict()
    data["carriages"][0]["profile"] = {"type": "sine", "amplitude": 0.1, "omega": 3.0}
    with pytest.raises(ScenarioError, match=r"carriages\[0\]\.profile: profile design needs a trapezoid or an"):
        move_designs(scenario_from_dict(data))
