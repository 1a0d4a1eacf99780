"""A top that bends conserves what it must: momentum with no isolators' stiffness and no gravity while the
carriages move, energy once they stop with nothing to damp it. Both are computed here from the states with
the carriages' kinetic energy ``m |r'|^2 / 2``, ``r`` including the feet's elastic translation (the contract),
independently of how the equations of motion were derived."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from synthetic_top import with_synthetic_top

from isolator import Simulator
from isolator.model.parameters import ParameterLayout
from isolator.simulation.points import rotation_matrices


def _carriage_paths(scenario, r):
    """Each carriage's table-frame position, velocity (rigid and elastic) [m, m/s] at the run's samples."""
    data = scenario.table.flexible.data
    layout = ParameterLayout.of(scenario)
    nm = data.n_modes
    eta, rate = r.states[:, 13:13 + nm], r.states[:, 13 + nm:13 + 2 * nm]
    q = np.array([c.profile.evaluate(r.t)[0] for c in scenario.carriages])
    qd = np.array([c.profile.evaluate(r.t)[1] for c in scenario.carriages])
    d = scenario.carriage_positions(q)  # (n, 3, N)
    dv = np.zeros_like(d)
    for i in scenario.carriage_order():
        c, parent = scenario.carriages[i], scenario.parent_indices()[i]
        dv[i] = (dv[parent] if parent >= 0 else 0.0) + np.asarray(c.axis)[:, None] * qd[i]
    out = []
    for i in range(len(scenario.carriages)):
        root = layout.flexible.carriages[i].root
        c = scenario.carriages[root]
        step = 1e-5

        def psi(qr, c=c):
            xy = np.asarray(c.origin)[None, :2] + np.asarray(c.axis)[None, :2] * qr[:, None]
            return data.translation(xy, data.face_for(c.origin[2]), "test")  # (N, n, 3)

        shape = psi(q[root])
        slope = (psi(q[root] + step) - psi(q[root] - step)) / (2 * step)
        e = np.einsum("nmi,nm->in", shape, eta)
        e_rate = np.einsum("nmi,nm->in", shape, rate) + np.einsum("nmi,nm->in", slope, eta) * qd[root]
        out.append((d[i] + e, dv[i] + e_rate))
    return out


def _momentum(scenario, r):
    rot = rotation_matrices(r.states, "exact")
    vel, w_body = r.states[:, 7:10], r.states[:, 10:13]
    w_world = np.einsum("nij,nj->ni", rot, w_body)
    total = scenario.table.mass * vel
    for c, (pos, v) in zip(scenario.carriages, _carriage_paths(scenario, r), strict=True):
        arm = np.einsum("nij,jn->ni", rot, pos)
        total = total + c.mass * (vel + np.cross(w_world, arm) + np.einsum("nij,jn->ni", rot, v))
    return total


def test_momentum_is_conserved_while_the_carriages_move_on_a_free_bending_top():
    base = with_synthetic_top(frequencies=(12.0, 18.0, 25.0))
    isolators = tuple(dataclasses.replace(iso, stiffness=(1e-9,) * 3, damping=(0.0,) * 3) for iso in base.isolators)
    scenario = dataclasses.replace(base, isolators=isolators, gravity=0.0,
                                   simulation=dataclasses.replace(base.simulation, duration=8.0))
    r = Simulator(scenario, elastic="dynamic").run()
    nm = 3
    assert np.max(np.abs(r.states[:, 13:13 + nm])) > 1e-5  # the moving loads do bend the top
    scale = sum(c.mass for c in scenario.carriages) * 0.2  # the carriages' momentum at speed [kg m/s]
    momentum = _momentum(scenario, r)
    assert np.max(np.abs(momentum)) < 1e-6 * scale
    # vertically the carriages move with the top's bending only: the moving load's terms must balance there too
    vertical = max(c.mass * np.max(np.abs(v[2])) for c, (_, v) in zip(scenario.carriages,
                                                                       _carriage_paths(scenario, r), strict=True))
    assert np.max(np.abs(momentum[:, 2])) < 1e-3 * vertical


def _energy(scenario, r):
    rot = rotation_matrices(r.states, "exact")
    vel, w_body = r.states[:, 7:10], r.states[:, 10:13]
    data = scenario.table.flexible.data
    nm = data.n_modes
    eta, rate = r.states[:, 13:13 + nm], r.states[:, 13 + nm:]
    inertia = np.asarray(scenario.table.inertia)
    g = scenario.gravity
    energy = 0.5 * scenario.table.mass * np.sum(vel**2, axis=1) + 0.5 * np.sum(inertia * w_body**2, axis=1)
    energy += 0.5 * np.sum(rate**2, axis=1) + 0.5 * np.sum((2 * np.pi * data.frequencies * eta) ** 2, axis=1)
    energy += scenario.table.mass * g * r.states[:, 2]
    w_world = np.einsum("nij,nj->ni", rot, w_body)
    for c, (pos, v) in zip(scenario.carriages, _carriage_paths(scenario, r), strict=True):
        arm = np.einsum("nij,jn->ni", rot, pos)
        speed = vel + np.cross(w_world, arm) + np.einsum("nij,jn->ni", rot, v)
        energy += 0.5 * c.mass * np.sum(speed**2, axis=1) + c.mass * g * (r.states[:, 2] + arm[:, 2])
    layout = ParameterLayout.of(scenario)
    preload = scenario.isolator_preloads()
    for k, iso in enumerate(scenario.isolators):
        shape = layout.flexible.shape_matrix(layout.flexible.isolators[k])
        s = np.asarray(iso.position)
        lever = s[None, :] + eta @ shape.T
        stretch = r.states[:, 0:3] + np.einsum("nij,nj->ni", rot, lever) - s[None, :]
        energy += 0.5 * np.sum(np.asarray(iso.stiffness) * stretch**2, axis=1) - preload[k] * stretch[:, 2]
    return energy


@pytest.mark.parametrize("frequencies", [(12.0, 18.0, 25.0), (150.0, 220.0, 310.0)])
def test_energy_is_constant_once_the_carriages_stop_with_nothing_to_damp(frequencies):
    base = with_synthetic_top(frequencies=frequencies, zeta=0.0)
    isolators = tuple(dataclasses.replace(iso, damping=(0.0,) * 3) for iso in base.isolators)
    scenario = dataclasses.replace(base, isolators=isolators,
                                   simulation=dataclasses.replace(base.simulation, duration=10.0))
    r = Simulator(scenario, elastic="dynamic").run()
    after = r.t > scenario.stop_time + 0.01
    energy = _energy(scenario, r)[after]
    vibration = np.ptp(_energy(scenario, r))  # the energy the moves put in and took out [J]
    assert vibration > 0
    assert np.ptp(energy) < 1e-6 * vibration
