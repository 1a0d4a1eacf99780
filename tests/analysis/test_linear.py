"""The linearised model against independent references.

* the MuJoCo model, linearised by central finite differences about its own
  equilibrium (matrices and eigenvalues);
* closed-form single-axis spring-damper transmissibility and compliance;
* the full time-varying simulation driven by small floor motion;
* the hand-calculated tipping limit (rocking stiffness sum kz y^2 - W h).
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from conftest import asymmetric_3d_dict, base_dict, make, tipping_dict
from isolator import ParameterError, Simulator, UnstableTableError
from isolator.analysis.linear import linearise
from isolator.analysis.modes import modes, modes_over_travel
from isolator.analysis.stability import stability
from isolator.analysis.transmissibility import compliance, transmissibility
from isolator.validation.multibody import MujocoTable, mujoco_available


# -- MuJoCo, finite differences -----------------------------------------------------
def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w1, v1, w2, v2 = a[0], a[1:], b[0], b[1:]
    return np.r_[w1 * w2 - v1 @ v2, w1 * v2 + w2 * v1 + np.cross(v1, v2)]


def _quat_of_rotvec(phi: np.ndarray) -> np.ndarray:
    angle = np.linalg.norm(phi)
    if angle == 0:
        return np.r_[1.0, 0, 0, 0]
    return np.r_[math.cos(angle / 2), math.sin(angle / 2) * phi / angle]


def _rot(qt: np.ndarray) -> np.ndarray:
    w, x, y, z = qt / np.linalg.norm(qt)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def _mujoco_rates(table: MujocoTable, y0: np.ndarray, positions: np.ndarray):
    """d/dt of (dp, phi, v, omega_world) from MuJoCo, as a function of the deviation and the floor."""
    rest = np.zeros((3, len(positions)))
    rest[0] = positions

    def rates(xi: np.ndarray, ground: np.ndarray) -> np.ndarray:
        qt = _quat_mul(_quat_of_rotvec(xi[3:6]), y0[3:7])
        rot = _rot(qt)
        y = np.r_[y0[0:3] + xi[0:3], qt, xi[6:9], rot.T @ xi[9:12]]
        acc = table.accelerations(y, rest, ground=ground)
        return np.r_[xi[6:9], xi[9:12], acc[0:3], rot @ acc[3:6]]

    return rates


@pytest.mark.skipif(not mujoco_available(), reason="needs mujoco")
@pytest.mark.parametrize("case", ["paper-3-1-like", "asymmetric-3d"])
def test_linearisation_matches_mujoco_finite_differences(case):
    data = base_dict() if case == "paper-3-1-like" else asymmetric_3d_dict()
    scenario = make(data)
    positions = np.array([c.profile.position(0.7) for c in scenario.carriages])
    lin = linearise(scenario, positions=positions)
    table = MujocoTable(scenario)
    y0 = table.equilibrium(positions)
    rates = _mujoco_rates(table, y0, positions)
    h = np.r_[np.full(3, 1e-6), np.full(3, 1e-6), np.full(3, 1e-5), np.full(3, 1e-5)]
    zero_g = np.zeros(12)
    a_fd = np.column_stack([
        (rates(h[i] * e, zero_g) - rates(-h[i] * e, zero_g)) / (2 * h[i]) for i, e in enumerate(np.eye(12))
    ])
    # the same system in the second-order form: x'' = -M^-1 (K x + C x' + G0 g + G1 g')
    inv_m = np.linalg.inv(lin.mass)
    a_ours = np.block([[np.zeros((6, 6)), np.eye(6)], [-inv_m @ lin.stiffness, -inv_m @ lin.damping]])
    scale = np.abs(a_ours[6:]).max()
    np.testing.assert_allclose(a_fd[6:], a_ours[6:], atol=1e-6 * scale)
    eig_fd = np.sort_complex(np.linalg.eigvals(a_fd))
    eig = np.sort_complex(lin.eigenvalues)
    np.testing.assert_allclose(eig_fd, eig, rtol=1e-6)
    # floor displacement and velocity terms
    xi0 = np.zeros(12)
    g_fd = np.column_stack([
        (rates(xi0, 1e-6 * e) - rates(xi0, -1e-6 * e)) / 2e-6 for e in np.eye(12)
    ])[6:]
    g_ours = -inv_m @ np.hstack([lin.ground_stiffness, lin.ground_damping])
    np.testing.assert_allclose(g_fd, g_ours, atol=1e-6 * np.abs(g_ours).max())


# -- one axis, closed form --------------------------------------------------------
def _decoupled_dict() -> dict:
    """Four equal isolators at the mass centre's height, symmetric: x, y, z decouple."""
    data = base_dict()
    data["carriages"] = []
    for iso in data["isolators"]:
        iso["position"][2] = 0.0
        iso["stiffness"] = [2.0e5, 2.5e5, 6.0e5]
        iso["damping"] = [1.5e3, 2.0e3, 4.0e3]
    return data


def test_single_axis_transmissibility_is_the_spring_damper_formula():
    scenario = make(_decoupled_dict())
    lin = linearise(scenario)
    f = np.logspace(-1, 2, 400)
    trans = transmissibility(lin, f)
    comp = compliance(lin, f)
    m = scenario.total_mass
    s = 2j * np.pi * f
    for k, axis in enumerate("xyz"):
        kk = sum(iso.stiffness[k] for iso in scenario.isolators)
        cc = sum(iso.damping[k] for iso in scenario.isolators)
        exact = (cc * s + kk) / (m * s**2 + cc * s + kk)
        np.testing.assert_allclose(trans.response[:, k, k], exact, rtol=1e-9)
        np.testing.assert_allclose(comp.response[:, k, k], 1 / (m * s**2 + cc * s + kk), rtol=1e-9)
        # |T| = 1 at sqrt(2) wn whatever the damping; the peak where d|T|/dw = 0
        wn = math.sqrt(kk / m)
        assert trans.isolation_onset(axis) == pytest.approx(math.sqrt(2) * wn / (2 * np.pi), rel=1e-8)
        zeta = cc / (2 * math.sqrt(kk * m))
        r_peak = math.sqrt(math.sqrt(1 + 8 * zeta**2) - 1) / (2 * zeta)
        value, f_peak = trans.peak(axis)
        assert f_peak == pytest.approx(r_peak * wn / (2 * np.pi), rel=1e-5)
        r2 = r_peak**2
        assert value == pytest.approx(math.sqrt((1 + 4 * zeta**2 * r2) / ((1 - r2) ** 2 + 4 * zeta**2 * r2)), rel=1e-9)
        mode = modes(lin)
        j = mode.dominant.index(axis)
        assert mode.frequencies_hz[j] == pytest.approx(wn / (2 * np.pi), rel=1e-9)
        assert mode.damping_ratios[j] == pytest.approx(zeta, rel=1e-9)


def test_scaled_isolators_give_the_scaled_spring_damper():
    scenario = make(_decoupled_dict())
    sim = Simulator(scenario)
    scaled = sim.scaled_parameters(2.5, 0.4)
    lin = linearise(scenario, parameters=scaled)
    assert np.array_equal(lin.parameters, scaled)
    f = np.logspace(-1, 2, 200)
    trans = transmissibility(lin, f)
    m, s = scenario.total_mass, 2j * np.pi * f
    for k in range(3):
        kk = 2.5 * sum(iso.stiffness[k] for iso in scenario.isolators)
        cc = 0.4 * sum(iso.damping[k] for iso in scenario.isolators)
        np.testing.assert_allclose(trans.response[:, k, k], (cc * s + kk) / (m * s**2 + cc * s + kk), rtol=1e-9)
    assert np.array_equal(linearise(scenario).parameters, sim.parameters)
    with pytest.raises(ParameterError, match="parameters: must be"):
        linearise(scenario, parameters=scaled[:-1])


# -- linear against the full simulation -----------------------------------------------
def test_linear_response_matches_full_simulation_for_small_floor_motion():
    data = asymmetric_3d_dict(duration=2.0)
    for c in data["carriages"]:
        start = c["profile"]["start"]
        c["profile"] = {"type": "samples", "t": [0.0, 0.5], "q": [start, start]}  # parked during the run
    motion = {"x": (2e-6, 9.0, 0.3), "z": (3e-6, 21.0, 0.0), "rx": (1e-6, 30.0, 1.0), "rz": (2e-6, 15.0, 0.5)}
    data["ground"] = {
        axis: {"type": "sine", "amplitude": a, "omega": w, "phase": ph, "offset": -a * math.sin(ph)}
        for axis, (a, w, ph) in motion.items()
    }
    scenario = make(data)
    full = Simulator(scenario).run()
    lin = linearise(scenario)
    sys = lin.system
    a, b = np.asarray(sys.A), np.asarray(sys.B)[:, :6]
    c, d = np.asarray(sys.C)[:6], np.asarray(sys.D)[:6, :6]

    def floor(t: float) -> np.ndarray:
        return scenario.ground.displacement(np.array([t]))[0, :6]

    sol = solve_ivp(lambda t, x: a @ x + b @ floor(t), (0, full.t[-1]), np.zeros(12), t_eval=full.t,
                    method="DOP853", rtol=1e-10, atol=1e-16)
    u = scenario.ground.displacement(full.t)[:, :6]
    y = c @ sol.y + d @ u.T
    for k in range(6):
        err = np.sqrt(np.mean((full.signals[k] - y[k]) ** 2)) / np.sqrt(np.mean(full.signals[k] ** 2))
        assert err < 1e-4, (k, err)


# -- tipping, hand calculation --------------------------------------------------------
def test_rocking_margin_and_tipping_limit_match_hand_calculation():
    data = tipping_dict(0.2)
    scenario = make(data)
    weight = scenario.gravity * scenario.total_mass
    kz_y2 = sum(iso.stiffness[2] * iso.position[1] ** 2 for iso in scenario.isolators)
    kz_x2 = sum(iso.stiffness[2] * iso.position[0] ** 2 for iso in scenario.isolators)
    assert kz_y2 < kz_x2  # rocking about x is the weak one
    rock = linearise(scenario).rocking_stiffness()
    # translations condensed: horizontal springs at one height drop out; the weight takes W h
    assert rock.margin == pytest.approx(kz_y2 - weight * 0.2, rel=1e-9)
    assert rock.weakest_axis == "rx"
    assert rock.elastic[0] == pytest.approx(kz_y2, rel=1e-9)
    critical = kz_y2 / weight
    below, above = make(tipping_dict(0.98 * critical)), make(tipping_dict(1.02 * critical))
    assert stability(below).stable
    report = stability(above)
    assert not report.stable
    assert report.margin == pytest.approx(kz_y2 - weight * 1.02 * critical, rel=1e-6)
    with pytest.raises(UnstableTableError, match="rocking stiffness about rx"):
        Simulator(above).run()
    with pytest.raises(UnstableTableError, match="rocking stiffness about rx"):
        linearise(above)


# -- configurations, inputs, outputs ----------------------------------------------------
def test_rest_configurations_and_named_signals():
    data = asymmetric_3d_dict()
    data["points"] = [{"name": "lens", "position": [0.5, -0.3, 0.4]}]
    data["actuators"] = [{"name": "z1", "position": [1.0, 0.6, -0.1], "direction": [0, 0, 1], "max_force": 500.0}]
    scenario = make(data)
    lin = linearise(scenario, time=0.0)
    assert lin.system.nstates == 12
    assert lin.output_names == ["x", "y", "z", "rx", "ry", "rz", "lens:x", "lens:y", "lens:z"]
    assert lin.input_names[-1] == "actuator:z1"
    moved = linearise(scenario, positions={"lower": 0.2})
    assert moved.positions[0] == 0.2
    assert moved.positions[1] == scenario.initial_positions()[1]
    at_end = linearise(scenario, time=10.0)
    np.testing.assert_allclose(at_end.positions, scenario.final_positions())
    # the point's motion is the mass centre's plus the rotation times its arm (static, 0 Hz)
    h = lin.frequency_response(np.array([0.0]), ["force:z", "torque:x", "actuator:z1"])[0]
    pose = lin.equilibrium.pose  # the table rests slightly tilted: arms turn with it
    rot0 = Rotation.from_euler("ZYX", pose[5:2:-1]).as_matrix()
    arm = rot0 @ np.array([0.5, -0.3, 0.4])
    expected = h[0:3] + np.cross(h[3:6].T, arm).T
    np.testing.assert_allclose(h[6:9], expected, rtol=1e-6, atol=1e-12 * np.abs(h).max())
    # an actuator along z at P acts as force:z plus the moment P x e_z
    direct = lin.frequency_response(np.array([0.0, 3.0]), ["actuator:z1"])[:, :, 0]
    p = rot0 @ np.array([1.0, 0.6, -0.1])
    torque = np.cross(p, [0, 0, 1.0])
    combo = lin.frequency_response(np.array([0.0, 3.0]), ["force:z", "torque:x", "torque:y", "torque:z"])
    np.testing.assert_allclose(direct, combo[:, :, 0] + combo[:, :, 1:] @ torque, rtol=1e-9,
                               atol=1e-9 * np.abs(direct).max())


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"positions": {"nope": 0.1}}, "positions.nope: no such carriage"),
        ({"positions": {"lower": float("nan")}}, "positions.lower: must be finite"),
        ({"positions": [0.1]}, "positions: needs 2 values"),
        ({"positions": {"lower": 5.0}}, "positions.lower: puts the carriage's mass"),
        ({"positions": {"lower": 0.1}, "time": 1.0}, "positions: give carriage positions or a time"),
        ({"time": -1.0}, "time: must be a finite time"),
    ],
)
def test_bad_rest_configurations_are_named(kwargs, message):
    with pytest.raises(ParameterError, match=message):
        linearise(make(asymmetric_3d_dict()), **kwargs)


def test_modes_follow_the_stage():
    data = copy.deepcopy(base_dict())
    scenario = make(data)
    centre = modes(linearise(scenario, positions=[0.0]))
    edge = modes(linearise(scenario, positions=[0.4]))
    assert not np.allclose(centre.frequencies_hz, edge.frequencies_hz, rtol=1e-6)
    assert np.all(np.diff(centre.frequencies_hz) >= 0)


def test_modes_over_travel_and_figures(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    scenario = make(asymmetric_3d_dict())
    travel = modes_over_travel(scenario, samples=5)
    assert travel.carriages == ("lower", "upper")
    assert travel.frequencies_hz[0].shape == (5, 6)
    # each sweep point equals a direct linearisation there
    direct = modes(linearise(scenario, positions={"upper": travel.positions[1][2]}))
    np.testing.assert_allclose(travel.frequencies_hz[1][2], direct.frequencies_hz, rtol=1e-12)
    for i, fig in enumerate((travel.plot(), direct.plot(), compliance(linearise(scenario)).plot())):
        fig.savefig(tmp_path / f"{i}.png")
        assert (tmp_path / f"{i}.png").stat().st_size > 10_000
    with pytest.raises(ParameterError, match="samples: must be a whole number from 2"):
        modes_over_travel(scenario, samples=1)
