"""Linear analysis of pneumatic tables against the hand-derived three-parameter (Zener) isolator."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from pneumatic_cases import pneumatic_dict, three_springs_dict

from isolator import linearise, load_scenario, modes, scenario_from_dict, simulate, transmissibility
from isolator.analysis.pneumatic import equivalent_spring_damper
from isolator.errors import ParameterError
from isolator.scenario.validation import rest_gauge_pressures

N_POLY = 1.4


def _hand_zener(p0: float, area: float, v1: float, v2: float, diameter: float, length: float,
                frequency_hz: np.ndarray, n: float = N_POLY, mu: float = 1.81e-5) -> np.ndarray:
    """Complex vertical stiffness of one air spring, from the contract's equations by hand.

    Linearised about p0 (absolute): V1 dp1/dt = -n p0 A ds/dt - n G p0 (p1 - p2), V2 dp2/dt = n G p0 (p1 - p2),
    F = A p1, so k(s) = n p0 A^2 / (V1 + V2 / (1 + s tau)) with tau = V2 / (n G p0).
    """
    g = math.pi * diameter**4 / (128 * mu * length)
    tau = v2 / (n * g * p0)
    s = 2j * np.pi * frequency_hz
    return n * p0 * area**2 / (v1 + v2 / (1 + s * tau))


def _symmetric_heave() -> tuple:
    data = pneumatic_dict(carriage=False)
    return scenario_from_dict(data), data


def test_heave_transmissibility_is_the_one_mass_zener_isolator():
    """Symmetric table, no carriage: floor-to-table z equals 4 k / (4 k + M s^2), k by hand (1e-6)."""
    s, data = _symmetric_heave()
    gauge = rest_gauge_pressures(s)
    np.testing.assert_allclose(gauge, gauge[0], rtol=1e-12)
    iso = data["isolators"][0]
    f = np.logspace(-1, 2, 61)
    k = _hand_zener(gauge[0] + 101325.0, iso["area"], iso["volume"], iso["damping_volume"],
                    iso["orifice"]["diameter"], iso["orifice"]["length"], f)
    s_ = 2j * np.pi * f
    expected = 4 * k / (4 * k + s.table.mass * s_**2)
    lin = linearise(s)
    got = lin.frequency_response(f, ["ground:z"], ["z"])[:, 0, 0]
    np.testing.assert_allclose(got, expected, rtol=1e-6)
    # the Zener shape: -40 dB/decade well above the resonance (a dashpot would give -20)
    t = transmissibility(lin, np.array([30.0, 300.0]))
    slope = np.log10(t.magnitude("z")[1] / t.magnitude("z")[0])
    assert slope == pytest.approx(-2.0, abs=0.05)


def test_heave_under_small_floor_motion_matches_the_linear_model():
    """The nonlinear simulation, 1 um floor sine at 3 Hz: the steady amplitude and phase of the linear model."""
    s, data = _symmetric_heave()
    f0 = 3.0
    data = copy.deepcopy(data)
    data["ground"] = {"z": {"type": "sine", "amplitude": 1e-6, "omega": 2 * math.pi * f0}}
    data["simulation"] = {"duration": 8.0, "sample_rate": 1000.0}
    run = simulate(scenario_from_dict(data))
    t, z = run.t, run.signal("z")
    last = t >= 5.0  # steady state: the slowest pole decays at 6/s or faster
    basis = np.column_stack([np.sin(2 * math.pi * f0 * t[last]), np.cos(2 * math.pi * f0 * t[last])])
    (a, b), *_ = np.linalg.lstsq(basis, z[last], rcond=None)
    measured = (a + 1j * b) / 1e-6  # sin -> 1, cos -> i
    expected = linearise(s).frequency_response(np.array([f0]), ["ground:z"], ["z"])[0, 0, 0]
    assert abs(measured - expected) < 2e-3 * abs(expected)


def test_equivalent_spring_damper_is_the_hand_zener():
    s = load_scenario("paper-table-3-2-pneumatic")
    f = np.array([0.0, 1.0, 3.45, 10.0])
    eq = equivalent_spring_damper(s, f, isolator="front-left")
    iso = s.isolators[0]
    k = _hand_zener(eq.gauge_pressure + 101325.0, iso.area, iso.volume, iso.damping_volume,  # type: ignore[union-attr]
                    iso.orifice.diameter, iso.orifice.length, f)  # type: ignore[union-attr]
    np.testing.assert_allclose(eq.stiffness, k.real, rtol=1e-12)
    np.testing.assert_allclose(eq.damping[1:], k.imag[1:] / (2 * np.pi * f[1:]), rtol=1e-12)
    # the bundled sizing: |k| at the paper's heave frequency is the paper's spring on average over the
    # isolators (their rest pressures differ by +-7 %), with the most loss there
    at_heave = equivalent_spring_damper(s, 3.45)
    assert isinstance(at_heave, dict)
    magnitude = [math.hypot(e.stiffness[0], e.damping[0] * 2 * math.pi * 3.45) for e in at_heave.values()]
    assert np.mean(magnitude) == pytest.approx(5.7e5, rel=0.02)
    dense = equivalent_spring_damper(s, np.linspace(2.0, 6.0, 401), isolator="front-left")
    assert dense.frequency_hz[np.argmax(dense.loss_factor)] == pytest.approx(3.45, rel=0.05)
    everyone = equivalent_spring_damper(s, 1.0)
    assert set(everyone) == {"front-left", "rear-left", "rear-right", "front-right"}


def test_equivalent_spring_damper_bad_arguments():
    s = load_scenario("paper-table-3-2-pneumatic")
    with pytest.raises(ParameterError, match=r"^isolator: no pneumatic isolator named 'middle'"):
        equivalent_spring_damper(s, 1.0, isolator="middle")
    with pytest.raises(ParameterError, match=r"^frequency_hz: must be finite"):
        equivalent_spring_damper(s, -1.0)
    with pytest.raises(ParameterError, match=r"^gauge_pressure:"):
        equivalent_spring_damper(s.isolators[0], 1.0)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"^target: the scenario's isolators are not pneumatic"):
        equivalent_spring_damper(load_scenario("paper-table-3-2"), 1.0)


def test_modes_report_relaxation_poles_apart():
    """Four air springs with damping chambers: six oscillating modes, real relaxation poles, three integrators."""
    lin = linearise(load_scenario("paper-table-3-2-pneumatic"))
    m = modes(lin)
    assert len(m.frequencies_hz) == 6
    assert m.integrators == 3  # one per leveling group: the air it holds, valves closed
    eig = lin.eigenvalues
    real = np.sort(-eig.real[(np.abs(eig.imag) < 1e-9) & (np.abs(eig) > 1e-6)])
    np.testing.assert_allclose(m.relaxation_rates, real, rtol=1e-12)
    assert len(m.relaxation_rates) + 2 * 6 + 3 == lin.system.nstates
    assert "relaxation poles" in m.summary()


def test_plain_air_springs_have_no_relaxation():
    lin = linearise(scenario_from_dict(three_springs_dict(damping_volume=0.0)))
    m = modes(lin)
    assert m.relaxation_rates.size == 0
    assert m.integrators == 3
    assert lin.system.nstates == 12 + 3
