"""Tipping and floor vibration with pneumatic isolators: the air springs' slow stiffness at the rest pressures."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pneumatic_cases import pneumatic_dict

from isolator import Simulator, UnstableTableError, linearise, scenario_from_dict, stability, vibration_criteria
from isolator.scenario.reader import load_spectrum

ROOT = Path(__file__).resolve().parents[2]


def _raised(height: float) -> dict:
    """Four corner air springs, no carriage, their attachment points ``height`` below the mass centre."""
    data = pneumatic_dict(carriage=False)
    for iso in data["isolators"]:
        iso["position"][2] = -height
    return data


def test_rocking_margin_and_tipping_limit_of_air_springs_match_hand_calculation():
    """About x only the rear pair resists slow rocking: the front pair shares one line, so rolling moves air
    from one to the other at one pressure. Each rear spring squeezed slowly: k_s = n p0 A^2 / (V1r + V2)."""
    s = scenario_from_dict(_raised(0.2))
    weight = s.gravity * s.total_mass
    air = s.air
    assert air is not None
    rear = s.isolators[1]
    p0 = weight / (4 * rear.area) + air.atmosphere  # the symmetric table: every spring at one pressure
    k_slow = air.polytropic * p0 * rear.area**2 / (rear.volume + rear.damping_volume)
    kz_y2 = 2 * k_slow * 0.5**2
    rock = linearise(s).rocking_stiffness()
    assert rock.weakest_axis == "rx"
    assert rock.margin == pytest.approx(kz_y2 - weight * 0.2, rel=1e-9)
    critical = kz_y2 / weight
    below, above = scenario_from_dict(_raised(0.98 * critical)), scenario_from_dict(_raised(1.02 * critical))
    assert stability(below).stable
    report = stability(above)
    assert not report.stable
    assert report.margin == pytest.approx(kz_y2 - weight * 1.02 * critical, rel=1e-6)
    with pytest.raises(UnstableTableError, match="rocking stiffness about rx"):
        Simulator(above).run()


def test_vibration_criteria_on_a_pneumatic_table():
    """The floor's one-third-octave velocities pass through the Zener isolator: amplified near the
    resonances, cut well above them."""
    s = scenario_from_dict(pneumatic_dict(carriage=False))
    spectrum = load_spectrum(ROOT / "docs" / "examples" / "floor-third-octave.csv", "third-octave")
    result = vibration_criteria(linearise(s), spectrum)
    f = result.centres
    floor, table = result.floor["z"], result.table["z"]
    high = f >= 20.0
    assert np.all(table[high] < 0.1 * floor[high])
    assert result.table_class in ("VC-A", "VC-B", "VC-C", "VC-D", "VC-E", "VC-F", "VC-G", "above VC-A")
