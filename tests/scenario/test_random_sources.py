"""Spectral densities of the error budget's sources (issue 32): their integral, a sensor's noise per sample."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from isolator.scenario.random_sources import SpectralDensity
from isolator.scenario.sensors import Sensor


@given(st.lists(st.floats(1e-6, 1e3), min_size=2, max_size=6, unique=True),
       st.lists(st.floats(1e-20, 1e-2), min_size=6, max_size=6), st.floats(0.05, 5e3))
def test_the_integral_is_the_power_laws_integral(freqs, values, high):
    f = tuple(sorted(freqs))
    if min(b / a for a, b in itertools.pairwise(f)) < 1.001:
        return
    density = SpectralDensity(tuple(values[: len(f)]), f)
    grid = np.geomspace(f[0], max(min(high, f[-1]), f[0] * 1.0000001), 400_001)
    numeric = np.trapezoid(density(grid), grid) if high > f[0] else 0.0
    assert density.integral(high) == pytest.approx(numeric, rel=1e-4, abs=1e-300)


def test_a_sensors_noise_per_sample():
    white = Sensor("g", "table", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "velocity", noise=3e-8)
    assert white.noise_rms(2000.0) == 3e-8
    assert white.noise_density(2000.0).value == (2 * 3e-8**2 / 2000.0,)  # type: ignore[union-attr]
    shaped = Sensor("g", "table", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "velocity",
                    noise_psd=SpectralDensity((1e-12, 1e-16, 1e-18), (0.1, 1.0, 10.0)))
    exact = 1e-12 * 0.1 / -3.0 * (10.0**-3 - 1) + 1e-16 * 1.0 / -1.0 * (10.0**-1 - 1)  # slopes -4 and -2
    assert shaped.noise_rms(2000.0) == pytest.approx(math.sqrt(exact), rel=1e-12)


def test_the_kalman_filter_assumes_a_spectrum_s_noise_per_sample():
    from controllers.feedback.output_designs import noise_model
    from controllers.feedback.sensor_plant import sensor_plant
    from isolator import linearise, load_scenario

    scenario = load_scenario("paper-table-3-2-budget")
    plant = sensor_plant(linearise(scenario))
    model = noise_model(plant, plant.discrete(2000.0))
    expected = [s.noise_rms(2000.0) for s in scenario.sensors]
    np.testing.assert_allclose(model.noise, expected, rtol=1e-12)
