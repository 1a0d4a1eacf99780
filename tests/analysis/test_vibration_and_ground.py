"""Floor spectra, vibration criteria, and the [ground] and [[points]] sections."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from conftest import base_dict, make
from isolator import ParameterError, ScenarioError
from isolator.analysis.linear import linearise
from isolator.analysis.vibration import VC_CLASSES, third_octave_bands, vibration_criteria
from isolator.scenario.definitions import FloorSpectrum
from isolator.scenario.tables import load_spectrum


def _decoupled() -> dict:
    data = base_dict()
    data["carriages"] = []
    for iso in data["isolators"]:
        iso["position"][2] = 0.0
    return data


def test_vc_classes_and_bands():
    assert VC_CLASSES["VC-A"] == pytest.approx(50e-6)
    assert VC_CLASSES["VC-G"] == pytest.approx(0.78e-6, rel=2e-3)
    centres, lower, upper = third_octave_bands(1.0, 80.0)
    assert centres[0] == pytest.approx(1.0)
    assert centres[-1] == pytest.approx(79.43, rel=1e-3)  # nominal 80 Hz band
    assert centres.size == 20
    np.testing.assert_allclose(upper[:-1], lower[1:])


def test_floor_bands_are_reproduced_and_the_table_follows_the_spring_damper():
    scenario = make(_decoupled())
    lin = linearise(scenario)
    centres, _, _ = third_octave_bands(0.5, 100.0)
    floor = FloorSpectrum("third-octave", centres, {"z": np.full(centres.size, 20e-6)})
    vc = vibration_criteria(lin, floor)
    np.testing.assert_allclose(vc.floor["z"], 20e-6, rtol=1e-12)
    assert vc.floor_class == "VC-B"
    # the table's band RMS is the integral of |T|^2 S over the band (S flat within it)
    m = scenario.total_mass
    k = sum(iso.stiffness[2] for iso in scenario.isolators)
    c = sum(iso.damping[2] for iso in scenario.isolators)

    def t2(f: float) -> float:
        s = 2j * math.pi * f
        return abs((c * s + k) / (m * s * s + c * s + k)) ** 2

    _, b2, b3 = third_octave_bands(1.0, 80.0)
    for j in (0, 5, 9, 19):
        density = (20e-6) ** 2 / (b3[j] - b2[j])
        expected = math.sqrt(quad(t2, b2[j], b3[j], epsabs=0, epsrel=1e-10)[0] * density)
        assert vc.table["z"][j] == pytest.approx(expected, rel=1e-4)
    assert np.all(vc.table["x"] < 1e-12 * vc.table["z"].max())  # decoupled: z floor moves only z
    worst = vc.table_max
    met = [n for n, lim in VC_CLASSES.items() if worst <= lim]
    assert vc.table_class == (met[-1] if met else "above VC-A")


def test_psd_spectrum_and_points(tmp_path: Path):
    data = _decoupled()
    data["points"] = [{"name": "corner", "position": [1.0, 0.5, 0.1]}]
    scenario = make(data)
    lin = linearise(scenario)
    path = tmp_path / "floor.csv"
    f = np.logspace(-0.5, 2.2, 60)
    path.write_text("frequency_hz,z\n" + "".join(f"{float(a)!r},1e-12\n" for a in f))
    spectrum = load_spectrum(path, "psd")
    vc = vibration_criteria(lin, spectrum, point="corner")
    assert vc.point == "corner"
    # flat PSD: the floor's band RMS is sqrt(S * bandwidth)
    _, lo, hi = third_octave_bands()
    np.testing.assert_allclose(vc.floor["z"], np.sqrt(1e-12 * (hi - lo)), rtol=1e-9)
    # at 1 Hz, below the 3.4 Hz modes, the table follows the floor, a little amplified
    assert 1.0 < vc.table["z"][0] / vc.floor["z"][0] < 1.15
    with pytest.raises(ParameterError, match="point: no point named 'nope'"):
        vibration_criteria(lin, spectrum, point="nope")
    with pytest.raises(ScenarioError, match=r"ground\.spectrum: no floor spectrum"):
        vibration_criteria(lin)


@pytest.mark.parametrize(
    ("section", "message"),
    [
        ({"ground": {"w": {"type": "sine", "amplitude": 1e-6, "omega": 10.0}}}, "ground.w: unknown key"),
        ({"ground": {"z": {"type": "wobble"}}}, "ground.z.type: unknown profile type"),
        ({"ground": {"spectrum": {"kind": "octave", "frequency": [1, 2], "z": [1, 1]}}},
         "ground.spectrum.kind: must be one of"),
        ({"ground": {"spectrum": {"kind": "psd", "frequency": [2, 1], "z": [1, 1]}}},
         "ground.spectrum: frequencies must be > 0 and strictly increasing"),
        ({"ground": {"spectrum": {"kind": "psd", "frequency": [1, 2], "z": [1, -1]}}},
         "ground.spectrum.z: values must be finite and >= 0"),
        ({"ground": {"spectrum": {"kind": "psd", "frequency": [1, 2]}}},
         "ground.spectrum: needs values for at least one of x, y, z"),
        ({"ground": {"spectrum": {"kind": "psd", "file": "missing.csv"}}}, "ground.spectrum.file: cannot read"),
        ({"points": [{"name": "a"}]}, "points\\[0\\].position: missing"),
        ({"points": [{"name": "a", "position": [0, 0, 0]}, {"name": "a", "position": [1, 0, 0]}]},
         "points\\[1\\].name: 'a' is used twice"),
        ({"points": [{"name": "a", "position": [0, 0, float("nan")]}]},
         "points\\[0\\].position\\[2\\]: must be finite"),
    ],
)
def test_ground_and_points_errors_are_named(section, message):
    data = base_dict()
    data.update(section)
    with pytest.raises(ScenarioError, match=message):
        make(data)


def test_spectrum_csv_columns_are_checked(tmp_path: Path):
    path = tmp_path / "bad.csv"
    path.write_text("frequency_hz,w\n1,2\n2,3\n")
    with pytest.raises(ScenarioError, match=r"^spectrum: '.*bad\.csv' line 1: column 'w' is not one of "):
        load_spectrum(path, "psd")
