"""The error budget (issue 32) against closed forms, a Lyapunov equation, its own bookkeeping, and bad input."""

from __future__ import annotations

import copy
import itertools
import math

import numpy as np
import pytest
from scipy.linalg import solve_continuous_lyapunov

from conftest import asymmetric_3d_dict, base_dict, make
from isolator import linearise
from isolator.analysis.budget import error_budget
from isolator.errors import ParameterError, ScenarioError

K, C, MASS = 4.0e5, 2.0e3, 1000.0  # per isolator: four of them under a 1000 kg table (heave zeta ~ 0.2 %)


def heave_dict(**extra: object) -> dict:
    """A symmetric table whose heave is one degree of freedom: 4 k, 4 c, mass ``MASS`` (no carriages)."""
    data = base_dict()
    data["carriages"] = []
    data["table"] = {"mass": MASS, "size": [2.0, 1.0, 0.2]}
    for iso in data["isolators"]:
        iso["stiffness"] = [K, K, K]
        iso["damping"] = [C, C, C]
    data.update(extra)
    return data


def white_floor_acceleration(level: float, axes: str = "z") -> dict:
    """``[ground.spectrum]`` of a floor whose acceleration PSD is ``level`` [(m/s^2)^2/Hz] at every frequency
    of 1e-4 .. 1e6 Hz: a velocity PSD falling as 1/f^2, exact under log-log interpolation."""
    f = [1e-4, 1e6]
    values = [level / (2 * math.pi * x) ** 2 for x in f]
    return {"spectrum": {"kind": "psd", "frequency": f, **dict.fromkeys(axes, values)}}


def test_heave_under_white_floor_acceleration_matches_the_closed_form():
    """Absolute acceleration of m z'' + c z' + k z = c g' + k g under white floor acceleration S0: its one-sided
    variance is S0 (c/m + k/c) / 4 (the standard integral of |(cs + k)/(ms^2 + cs + k)|^2)."""
    s0 = 1e-12  # (m/s^2)^2/Hz: a quiet floor (its velocity, S0 / (2 pi f)^2, within the plausible at 1e-4 Hz)
    scenario = make(heave_dict(ground=white_floor_acceleration(s0)))
    budget = error_budget(scenario, quantity="acceleration", band=(1e-3, 1e5))
    k, c = 4 * K, 4 * C
    exact = math.sqrt(s0 * (c / MASS + k / c) / 4)
    tail = s0 * c**2 / (MASS**2 * 4 * math.pi**2 * 1e5)  # above the band: |H|^2 ~ (c / m w)^2
    exact_in_band = math.sqrt(exact**2 - tail)
    assert budget.value("table", "z") == pytest.approx(exact_in_band, rel=5e-3)
    assert budget.value("table", "z", "floor:z") == pytest.approx(budget.value("table", "z"), rel=1e-12)


def test_white_force_on_the_real_table_matches_the_lyapunov_equation():
    """A flat force PSD on an asymmetric, lightly damped table with two carriages: the point's displacement
    variance from the Lyapunov equation of the linear model (no frequency grid at all)."""
    data = asymmetric_3d_dict()
    for iso in data["isolators"]:
        iso["damping"] = [v / 20 for v in iso["damping"]]  # 0.1 .. 0.5 % damping: narrow peaks
    data["points"] = [{"name": "probe", "position": [0.4, -0.3, 0.2]}]
    density = 3.0e-2
    data["disturbances"] = [{"name": "push", "position": [0.5, 0.2, 0.1], "direction": [0.6, 0.0, 0.8],
                             "psd": density}]
    scenario = make(data)
    lin = linearise(scenario)
    budget = error_budget(lin, band=(1e-4, 1e4))
    sys = lin.system
    names = list(sys.input_labels)
    force = [names.index(n) for n in ("force:x", "force:y", "force:z", "torque:x", "torque:y", "torque:z")]
    from isolator.model.rotations import pose_rotation

    direction = np.array([0.6, 0.0, 0.8])
    arm = pose_rotation(lin.equilibrium.pose[3:6]) @ np.array([0.5, 0.2, 0.1])
    b = np.asarray(sys.B)[:, force] @ np.concatenate([direction, np.cross(arm, direction)])
    a = np.asarray(sys.A)
    # one-sided PSD S per Hz is white noise of intensity S / 2: A P + P A' + B (S/2) B' = 0
    p = solve_continuous_lyapunov(a, -np.outer(b, b) * density / 2)
    outputs = list(sys.output_labels)
    for j, axis in enumerate("xyz"):
        c_row = np.asarray(sys.C)[outputs.index(f"probe:{axis}")]
        exact = math.sqrt(c_row @ p @ c_row)
        assert budget.value("probe", axis) == pytest.approx(exact, rel=5e-3), axis
        assert budget.rms[0, j] == pytest.approx(exact, rel=5e-3)


def test_shares_cumulative_and_quantities_are_consistent():
    data = heave_dict(ground={"spectrum": {"vc": "VC-D"}},
                      points=[{"name": "probe", "position": [0.3, 0.2, 0.1]},
                              {"name": "lens", "position": [-0.5, 0.1, 0.1]}],
                      disturbances=[{"name": "air", "position": [0.0, 0.4, 0.0], "direction": [0.0, 1.0, 0.0],
                                     "psd": {"frequency": [2.0, 20.0, 200.0], "value": [1e-2, 1e-3, 1e-5]}}])
    data["actuators"] = [{"name": "za", "position": [1.0, 0.5, -0.15], "direction": [0, 0, 1.0],
                          "max_force": 100.0, "noise_psd": 1e-4}]
    scenario = make(data)
    disp = error_budget(scenario)
    assert disp.sources == ("floor:x", "floor:y", "floor:z", "force:air", "actuator:za")
    np.testing.assert_allclose(np.sqrt((disp.source_rms**2).sum(axis=2)), disp.rms, rtol=1e-12)
    np.testing.assert_allclose(disp.cumulative[..., -1], disp.rms, rtol=1e-9)
    assert np.all(np.diff(disp.cumulative, axis=-1) >= 0)
    for quantity, power in (("velocity", 1), ("acceleration", 2)):
        other = error_budget(scenario, quantity=quantity)
        # each grid is refined for its own integrand from the same start: compare where both have points
        shared, mine, theirs = np.intersect1d(disp.frequency, other.frequency, return_indices=True)
        assert shared.size > 0.9 * disp.frequency.size
        np.testing.assert_allclose(other.psd[..., theirs], disp.psd[..., mine] * (2 * np.pi * shared) ** (2 * power),
                                   rtol=1e-9, atol=0)
    # the JSON of the contract
    out = disp.to_dict()
    assert out["quantity"] == "displacement"
    assert out["controller"] is None
    assert out["band"] == [0.1, 1000.0]
    assert out["points"]["lens"]["z"]["rms"] == pytest.approx(disp.value("lens", "z"))
    assert set(out["points"]["probe"]["y"]["sources"]) == set(disp.sources)


def test_vc_floor_is_the_class_limit_in_each_third_octave_band():
    """A VC-C floor has 12.5 µm/s RMS in each band from 1 to 79.4 Hz: the floor's own velocity, integrated over
    one band, gives it back (the budget's sources are the floor's translation, velocity = 2 pi f times it)."""
    scenario = make(heave_dict(ground={"spectrum": {"vc": "VC-C"}}))
    spectrum = scenario.ground.spectrum
    edges = spectrum.edges
    assert edges[0] == pytest.approx(0.891, rel=1e-3)
    assert edges[-1] == pytest.approx(89.1, rel=1e-3)
    for low, high in itertools.pairwise(edges):
        f = np.linspace(low * (1 + 1e-9), high * (1 - 1e-9), 2001)
        band_rms = math.sqrt(np.trapezoid(spectrum.velocity_psd("z", f), f))
        assert band_rms == pytest.approx(12.5e-6, rel=1e-6)


def test_a_narrow_resonance_between_grid_points_is_found():
    """Damping so light that the heave peak's half-power width is a few millihertz: the RMS still equals the
    Lyapunov value (a fixed log grid of 60 points per decade would be off by far more than 0.5 %)."""
    data = heave_dict()
    for iso in data["isolators"]:
        iso["damping"] = [5.0, 5.0, 5.0]
    data["disturbances"] = [{"name": "z", "position": [0.0, 0.0, 0.0], "direction": [0, 0, 1.0], "psd": 1.0}]
    budget = error_budget(make(data), band=(1e-3, 1e4))
    exact = math.sqrt(1.0 / (4 * (4 * K) * (4 * 5.0)))  # S / (4 k c)
    assert budget.value("table", "z") == pytest.approx(exact, rel=5e-3)


@pytest.mark.parametrize(("change", "message"), [
    (lambda d: d["disturbances"][0].update(psd=-1.0), "disturbances[0].psd: must be >= 0"),
    (lambda d: d["disturbances"][0].update(psd=float("nan")), "disturbances[0].psd: must be finite"),
    (lambda d: d["disturbances"][0].update(psd={"frequency": [1.0, 1.0], "value": [1.0, 2.0]}),
     "disturbances[0].psd.frequency[1]: frequencies must be strictly increasing"),
    (lambda d: d["disturbances"][0].update(psd={"frequency": [1.0, 2.0], "value": [1.0, 0.0]}),
     "disturbances[0].psd.value[1]: a power spectral density must be > 0"),
    (lambda d: d["disturbances"][0].update(direction=[0.0, 0.0, 2.0]),
     "disturbances[0].direction: must be a unit vector"),
    (lambda d: d["disturbances"].append(dict(d["disturbances"][0])), "disturbances[1].name: 'push' is used twice"),
    (lambda d: d.update(ground={"spectrum": {"vc": "VC-Z"}}), "ground.spectrum.vc: unknown vibration criterion"),
    (lambda d: d.update(ground={"spectrum": {"vc": "VC-C", "kind": "psd"}}), "ground.spectrum.vc: a VC class"),
    (lambda d: d.update(sensors=[{"name": "g", "on": "table", "position": [0, 0, 0], "direction": [0, 0, 1.0],
                                  "quantity": "velocity", "noise": 1e-9, "noise_psd": 1e-16}]),
     "sensors[0].noise_psd: give noise"),
    (lambda d: d["disturbances"][0].update(psd={"frequency": [1.0, 2.0], "value": [1.0]}),
     "disturbances[0].psd: needs at least two frequencies and one value per frequency"),
])
def test_bad_budget_keys_name_the_key(change, message):
    data = heave_dict(disturbances=[{"name": "push", "position": [0.0, 0.0, 0.0], "direction": [0, 0, 1.0],
                                     "psd": 1.0}])
    change(data)
    with pytest.raises(ScenarioError, match=None) as info:
        make(copy.deepcopy(data))
    assert str(info.value).startswith(message), str(info.value)


def test_bad_budget_arguments_name_the_argument():
    scenario = make(heave_dict(disturbances=[{"name": "push", "position": [0.0, 0.0, 0.0],
                                              "direction": [0, 0, 1.0], "psd": 1.0}]))
    with pytest.raises(ParameterError, match="points: no point named 'lens'"):
        error_budget(scenario, points=["lens"])
    with pytest.raises(ParameterError, match="band: must be 0 < low < high"):
        error_budget(scenario, band=(0.0, 10.0))
    with pytest.raises(ParameterError, match="band: must be 0 < low < high"):
        error_budget(scenario, band=(10.0, 1.0))
    with pytest.raises(ParameterError, match="band: must be two finite"):
        error_budget(scenario, band=(1.0, float("inf")))
    with pytest.raises(ParameterError, match="quantity: must be one of"):
        error_budget(scenario, quantity="jerk")
    with pytest.raises(ScenarioError, match="no random source"):
        error_budget(make(heave_dict()))
