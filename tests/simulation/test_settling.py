"""The settling-time definition on signals with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from isolator import Settling, settling_time
from isolator.simulation.settling import settling_metrics


def test_damped_cosine_settles_when_its_last_excursion_leaves_the_band():
    t = np.arange(0, 20, 1e-4)
    stop, zeta, wn = 2.0, 0.05, 2 * math.pi
    s = np.where(t < stop, 1.0, np.exp(-zeta * wn * (t - stop)) * np.cos(wn * (t - stop)))
    band = 0.05
    ts, reason = settling_time(t, s, 0.0, stop, band)
    assert reason == ""
    # the last sample outside the band, found by brute force on the analytic signal
    after = t >= stop
    last = t[after][np.nonzero(np.abs(s[after]) > band)[0][-1]]
    assert ts == pytest.approx(last - stop)
    # and it lies within one half-period before the envelope crosses the band
    envelope_time = math.log(1 / band) / (zeta * wn)
    assert envelope_time - 0.5 <= ts <= envelope_time


def test_inside_from_the_stop_is_zero_and_unfinished_runs_say_so():
    t = np.linspace(0, 10, 1001)
    assert settling_time(t, np.zeros_like(t), 0.0, 5.0, 1e-6) == (0.0, "")
    time, reason = settling_time(t, np.sin(t), 0.0, 5.0, 0.1)
    assert time is None
    assert "lengthen simulation.duration" in reason
    time, reason = settling_time(t, np.zeros_like(t), 0.0, 12.0, 0.1)
    assert time is None
    assert "before the carriages stop" in reason
    time, reason = settling_time(t, np.zeros_like(t), 0.0, math.inf, 0.1)
    assert time is None
    assert "never stops" in reason


def test_absolute_tolerance_band_and_final_value():
    t = np.linspace(0, 10, 10001)
    s = np.vstack([2e-6 + 1e-5 * np.exp(-(t - 1).clip(0)) * (t >= 1)] * 6)
    out = settling_metrics(t, s, np.full(6, 2e-6), 1.0, Settling(fraction=None, tolerance=(1e-6, 2e-6)))
    assert out["x"].time == pytest.approx(math.log(10), abs=2e-3)  # 1e-5 e^{-t} = 1e-6
    assert out["rx"].time == pytest.approx(math.log(5), abs=2e-3)  # 1e-5 e^{-t} = 2e-6
