"""Motion profiles: closed-form properties, continuity and limits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from isolator import SineProfile, samples, scurve, trapezoid


def _numeric_derivative(profile, t, h=1e-6):
    qp = profile.evaluate(t + h, t)[0]
    qm = profile.evaluate(t - h, t)[0]
    return (qp - qm) / (2 * h)


@pytest.mark.parametrize(
    ("stroke", "velocity", "accel", "decel"),
    [(1.4, 0.2, 0.5, None), (-0.6, 0.083, 0.5, None), (0.05, 1.0, 2.0, 4.0), (0.3, 0.5, 1.0, 0.5)],
)
def test_trapezoid_is_rest_to_rest_within_limits(stroke, velocity, accel, decel):
    p = trapezoid(start=0.2, stroke=stroke, velocity=velocity, acceleration=accel, t0=0.5,
                  deceleration=decel)
    t = np.linspace(0, p.stop_time + 1, 20001)
    q, v, a = p.evaluate(t)
    assert q[0] == pytest.approx(0.2)
    assert q[-1] == pytest.approx(0.2 + stroke, abs=1e-12)
    assert np.all(np.abs(v) <= velocity * (1 + 1e-12))
    dec = decel or accel
    assert np.all(np.abs(a) <= max(accel, dec) * (1 + 1e-12))
    # closed form of the move time
    peak = min(velocity, math.sqrt(2 * abs(stroke) * accel * dec / (accel + dec)))
    expected = peak / accel + peak / dec + max(abs(stroke) - peak**2 * (1 / accel + 1 / dec) / 2, 0) / peak
    assert p.stop_time - 0.5 == pytest.approx(expected, rel=1e-12)
    # velocity is the derivative of position away from the corners
    inner = t[(t > 0.51) & (t < p.stop_time - 0.01)]
    inner = inner[np.min(np.abs(inner[:, None] - np.array(p.breakpoints)[None, :]), axis=1) > 1e-4]
    assert np.allclose(_numeric_derivative(p, inner), p.evaluate(inner)[1], atol=1e-7)


def test_triangular_trapezoid_never_reaches_cruise_speed():
    p = trapezoid(start=0.0, stroke=0.01, velocity=1.0, acceleration=1.0)
    v = p.evaluate(np.linspace(0, p.stop_time, 1001))[1]
    assert v.max() == pytest.approx(math.sqrt(0.01), rel=1e-3)
    assert len(p.breakpoints) == 3  # no cruise piece


@pytest.mark.parametrize(
    ("stroke", "velocity", "accel", "jerk"),
    [(1.4, 0.2, 0.5, 5.0), (0.02, 1.0, 2.0, 10.0), (0.3, 1.0, 2.0, 1000.0), (-0.5, 0.3, 0.4, 0.8)],
)
def test_scurve_is_jerk_limited_and_continuous(stroke, velocity, accel, jerk):
    p = scurve(start=0.0, stroke=stroke, velocity=velocity, acceleration=accel, jerk=jerk, t0=0.3)
    t = np.linspace(0, p.stop_time + 0.5, 40001)
    q, v, a = p.evaluate(t)
    assert q[-1] == pytest.approx(stroke, abs=1e-12)
    assert np.all(np.abs(v) <= velocity * (1 + 1e-9))
    assert np.all(np.abs(a) <= accel * (1 + 1e-9))
    # acceleration continuous: left and right limits agree at every breakpoint
    for b in p.breakpoints:
        left = p.evaluate(np.array([b]), np.array([b - 1e-9]))[2]
        right = p.evaluate(np.array([b]), np.array([b + 1e-9]))[2]
        assert left == pytest.approx(right, abs=1e-9)
    jerk_num = np.diff(a) / np.diff(t)
    assert np.max(np.abs(jerk_num)) <= jerk * (1 + 1e-6)


def test_sine_holds_before_t0_and_never_stops():
    p = SineProfile(amplitude=0.7, omega=2.0, phase=-math.pi / 2, t0=1.0)
    q, v, _a = p.evaluate(np.array([0.0, 0.5, 1.0, 1.0 + math.pi / 2]))
    assert q[:3] == pytest.approx([-0.7, -0.7, -0.7])
    assert v[:2] == pytest.approx([0, 0])
    assert q[3] == pytest.approx(0.7)
    assert math.isinf(p.stop_time)
    assert p.final_position is None


def test_samples_spline_is_clamped_and_interpolates():
    t = np.array([0.5, 1.0, 1.5, 2.5])
    q = np.array([0.0, 0.1, 0.4, 0.5])
    p = samples(t, q)
    assert p.evaluate(t)[0] == pytest.approx(q)
    v_ends = p.evaluate(t[[0, -1]], t[[0, -1]] + np.array([1e-9, -1e-9]))[1]
    assert v_ends == pytest.approx([0.0, 0.0], abs=1e-12)
    assert p.position(0.0) == pytest.approx(0.0)
    assert p.position(10.0) == pytest.approx(0.5)
    mid = np.linspace(0.6, 2.4, 50)
    assert np.allclose(_numeric_derivative(p, mid), p.evaluate(mid)[1], atol=1e-6)
