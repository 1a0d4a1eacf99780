"""Physics invariants: momentum, energy, statics by hand, symmetry."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from conftest import asymmetric_3d_dict, base_dict, make
from isolator import ParameterLayout, Simulator, UnstableTableError, get_model, simulate
from isolator.model.equilibrium import static_equilibrium


def _rotations(states: np.ndarray) -> np.ndarray:
    w, x, y, z = (states[:, 3 + i] for i in range(4))
    n = np.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def _bodies(sc, r):
    """World positions and velocities of the table's and carriages' mass centres."""
    R = _rotations(r.states)
    pos_g, vel_g, w_body = r.states[:, 0:3], r.states[:, 7:10], r.states[:, 10:13]
    t = r.t
    qs = np.array([c.profile.evaluate(t)[0] for c in sc.carriages])
    vs = np.array([c.profile.evaluate(t)[1] for c in sc.carriages])
    d = sc.carriage_positions(qs)  # (n, 3, N) table frame
    dd = sc.carriage_positions(vs) - sc.carriage_positions(np.zeros_like(vs))  # rates: axes * q'
    out = []
    for i, c in enumerate(sc.carriages):
        di, ddi = d[i].T, dd[i].T
        p = pos_g + np.einsum("nij,nj->ni", R, di)
        v = vel_g + np.einsum("nij,nj->ni", R, ddi + np.cross(w_body, di))
        out.append((c.mass, p, v))
    return R, pos_g, vel_g, w_body, out


def test_free_floating_system_keeps_its_mass_centre_and_zero_angular_momentum():
    data = asymmetric_3d_dict(duration=3.0)
    data["gravity"] = 0.0
    for iso in data["isolators"]:
        iso["stiffness"] = [0.0, 0.0, 0.0]
        iso["damping"] = [0.0, 0.0, 0.0]
    sc = make(data)
    r = simulate(sc)
    R, pos_g, vel_g, w_body, carriages = _bodies(sc, r)
    M = sc.table.mass
    total = M + sum(m for m, _, _ in carriages)
    com = (M * pos_g + sum(m * p for m, p, _ in carriages)) / total
    drift = np.max(np.linalg.norm(com - com[0], axis=1))
    travel = np.max(np.linalg.norm(carriages[0][1] - carriages[0][1][0], axis=1))
    assert travel > 0.3  # the carriages really move ...
    assert drift < 1e-9 * travel  # ... and the system's mass centre does not
    J = np.diag(sc.table.inertia)
    L = np.einsum("nij,nj->ni", R, w_body @ J.T) + M * np.cross(pos_g - com, vel_g)
    for m, p, v in carriages:
        L += m * np.cross(p - com, v)
    scale = max(m * np.max(np.linalg.norm(v, axis=1)) for m, _, v in carriages) * 1.0
    assert np.max(np.abs(L)) < 1e-9 * scale
    assert np.max(np.abs(r.signals[3:])) > 1e-4  # the table turned: the test has teeth


def test_energy_balance_without_damping_matches_the_work_of_the_drives():
    data = base_dict()
    data["simulation"] = {"duration": 3.0, "sample_rate": 4000.0}
    for iso in data["isolators"]:
        iso["damping"] = [0.0, 0.0, 0.0]
    sc = make(data)
    r = simulate(sc)
    R, pos_g, vel_g, w_body, carriages = _bodies(sc, r)
    g = sc.gravity
    J = np.diag(sc.table.inertia)
    kinetic = 0.5 * sc.table.mass * np.sum(vel_g**2, 1) + 0.5 * np.einsum("ni,ij,nj->n", w_body, J, w_body)
    potential = sc.table.mass * g * pos_g[:, 2]
    for m, p, v in carriages:
        kinetic += 0.5 * m * np.sum(v**2, 1)
        potential += m * g * p[:, 2]
    kz = np.array([iso.stiffness[2] for iso in sc.isolators])
    preload = kz * g * sc.total_mass / kz.sum()
    for k, iso in enumerate(sc.isolators):
        s = np.asarray(iso.position)
        disp = pos_g + np.einsum("nij,j->ni", R, s) - s
        potential += 0.5 * np.sum(np.asarray(iso.stiffness) * disp**2, 1) - preload[k] * disp[:, 2]
    energy = kinetic + potential
    # work of the drive: force along the axis times the carriage's speed along it
    m, p, v = carriages[0]
    acc = np.gradient(v, r.t, axis=0, edge_order=2)
    axis_world = np.einsum("nij,j->ni", R, np.asarray(sc.carriages[0].axis))
    force = np.sum(axis_world * m * (acc - np.array([0, 0, -g])), 1)
    qdot = sc.carriages[0].profile.evaluate(r.t)[1]
    power = force * qdot
    work = np.concatenate([[0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(r.t))])
    mismatch = np.max(np.abs(energy - energy[0] - work))
    table_energy = np.max(np.abs(potential - potential[0] - (m * g * (p[:, 2] - p[0, 2]))))
    assert table_energy > 1e-3  # the isolators do store energy during the move
    assert mismatch < 2e-3 * table_energy, (mismatch, table_energy)


def test_static_tilt_matches_hand_calculation_with_preload():
    """theta = m g a / (sum kz x^2 - W hs - m g h) for a parked carriage (W: total weight)."""
    k, hs, h, a, m, M, g = 5.7e5, 0.15, 0.35, 0.6, 0.4, 4400.0, 9.81
    data = base_dict()
    data["carriages"][0].update(mass=m, profile={"type": "trapezoid", "start": a, "stroke": 0.0,
                                                 "velocity": 1.0, "acceleration": 1.0})
    sc = make(data)
    layout = ParameterLayout.of(sc)
    p = layout.pack(sc)
    kr = 4 * k * 1.0**2
    W = (M + m) * g
    exact = static_equilibrium(get_model(layout, "exact"), p, np.array([a]))
    # the vertical sag is zero with the combined mass centre kept over the isolator centroid to first order
    assert exact.pose[4] == pytest.approx(m * g * a / (kr - W * hs - m * g * h), rel=1e-6)
    assert exact.pose[0] == pytest.approx(hs * exact.pose[4], rel=1e-6)  # horizontal springs unloaded
    paper = static_equilibrium(get_model(layout, "paper"), p, np.array([a]))
    assert paper.pose[4] == pytest.approx(m * g * a / (kr - m * g * h), rel=1e-6)  # no preload term


def test_tipping_table_is_reported():
    data = base_dict()
    for iso in data["isolators"]:
        iso["position"] = [iso["position"][0] * 0.05, iso["position"][1] * 0.05, -0.15]
    data["table"]["size"] = [2.0, 1.0, 0.3]
    with pytest.raises(UnstableTableError, match=r"UNSTABLE: the table would tip; smallest rocking stiffness"):
        simulate(make(data))


def test_mirror_symmetry():
    data = base_dict()
    mirrored = copy.deepcopy(data)
    prof = mirrored["carriages"][0]["profile"]
    prof["start"], prof["stroke"] = -prof["start"], -prof["stroke"]
    r1 = simulate(make(data))
    r2 = simulate(make(mirrored))
    # mirror x -> -x: x, ry, rz... flip; z, rx, y keep (y, rx, rz are zero here)
    sign = np.array([-1, 1, 1, 1, -1, -1])[:, None]
    np.testing.assert_allclose(r2.signals, sign * r1.signals, atol=1e-12 * np.abs(r1.signals).max())
    assert np.max(np.abs(r1.signals[[1, 3, 5]])) < 1e-12
    assert np.abs(r1.signals[4]).max() > 1e-5


def test_batch_equals_single_runs():
    data = base_dict()
    data["simulation"]["duration"] = 8.0
    sim = Simulator(make(data))
    batch = sim.run_batch([1.0, 1.3], [1.0, 0.7])
    single = sim.run(p=sim.scaled_parameters(1.3, 0.7))
    assert batch.settling_time_max[1] == pytest.approx(single.settling_time_max)
    assert batch.peak[1] == pytest.approx(list(single.peak.values()))
