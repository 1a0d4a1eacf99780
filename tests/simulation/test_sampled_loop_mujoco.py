"""The compiled closed loop with an exported controller (docs/scenario-format.md, "Sensors in the scenario, output
feedback and exported controllers") against the same loop written here in numpy on a plant that owes nothing to the
toolkit's casadi model: MuJoCo's accelerations (the multibody check) differentiated about MuJoCo's own equilibrium,
and the geophones' rows built here from their geometry."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from isolator import Simulator, scenario_from_dict
from isolator.scenario.definitions import SIGNALS
from isolator.simulation.actuation import ForceHistory
from isolator.simulation.discrete_controller import DiscreteController

pytest.importorskip("mujoco")

from isolator.validation.multibody import MujocoTable
from sampled_loops import RATE, dynamic, geophone_data, pulse, settling

TOLERANCE = 1e-4  # of each signal's peak (see the test)


def quat_mul(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    return np.r_[p[0] * q[0] - p[1:] @ q[1:], p[0] * q[1:] + q[0] * p[1:] + np.cross(p[1:], q[1:])]


def quat_matrix(q: np.ndarray) -> np.ndarray:
    w, v = q[0], q[1:]
    cross = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + 2 * w * cross + 2 * cross @ cross


def mujoco_plant(s) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A (12, 12), B (12, actuators), the six signals' rows (6, 12) and the sensors' rows (sensors, 12) about
    MuJoCo's static equilibrium with the carriages parked. State: displacement of the mass centre, rotation
    vector ``d`` of the body-frame perturbation ``q = q0 (x) exp(d)``, world velocity, table-frame angular
    velocity ``w`` (MuJoCo's free joint); then ``d' = w`` and the signals' rotation (of ``R R0^T``) is ``R0 d``."""
    force = np.zeros(len(s.actuators))
    table = MujocoTable(s, forces=lambda t, piece: force)
    parked = np.zeros((3, len(s.carriages)))
    parked[0] = s.initial_positions()
    y0 = table.equilibrium(parked[0])
    r0 = quat_matrix(y0[3:7])

    def acc(x: np.ndarray) -> np.ndarray:
        angle = np.linalg.norm(x[3:6])
        dq = np.r_[np.cos(angle / 2), 0.5 * np.sinc(angle / (2 * np.pi)) * x[3:6]]
        return table.accelerations(np.r_[y0[:3] + x[:3], quat_mul(y0[3:7], dq), x[6:12]], parked)

    assert np.abs(acc(np.zeros(12))).max() < 1e-9  # MuJoCo's own rest
    a = np.zeros((12, 12))
    a[0:6, 6:12] = np.eye(6)
    for i, h in enumerate(np.r_[np.full(6, 1e-6), np.full(6, 1e-4)]):  # m, rad; m/s, rad/s
        e = np.zeros(12)
        e[i] = h
        a[6:, i] = (acc(e) - acc(-e)) / (2 * h)
    b = np.zeros((12, len(s.actuators)))
    for j in range(len(s.actuators)):
        force[j] = 1.0  # the forces enter affinely: one difference is exact
        b[6:, j] = acc(np.zeros(12))
        force[j] = 0.0
    b[6:] -= acc(np.zeros(12))[:, None]
    signals = np.zeros((6, 12))
    signals[0:3, 0:3], signals[3:6, 3:6] = np.eye(3), r0
    # a geophone reads n . (v + W x R0 r), W = R0 w the world angular velocity: n . v + n . R0 (w x r)
    sensors = np.zeros((len(s.sensors), 12))
    for k, sensor in enumerate(s.sensors):
        n, r = np.asarray(sensor.direction, dtype=float), np.asarray(sensor.position, dtype=float)
        assert sensor.on == "table"
        assert sensor.quantity == "velocity"
        sensors[k, 6:9] = n
        sensors[k, 9:12] = [n @ r0 @ np.cross(e, r) for e in np.eye(3)]
    return a, b, signals, sensors


def numpy_loop(s, plant, ctrl: DiscreteController, forces: ForceHistory, delay: bool | None = None,
               lag: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The contract's loop: readings at t_k, u_k = C x_k + D y_k held until t_{k+1} (t_{k+2} with delay), the
    feedforward added, clipped at max_force, the 200 Hz first-order lag; plant and lag sampled exactly over a
    tick (the command is constant in between). Returns the ticks and the six signals there (6, ticks)."""
    a, b, c_sig, c_sens = plant
    delay = ctrl.delay if delay is None else delay
    n, m = a.shape[0], b.shape[1]
    limit = np.array([x.max_force for x in s.actuators])
    if lag:
        tau = 1.0 / (2 * np.pi * s.actuators[0].bandwidth)
        assert all(x.bandwidth == s.actuators[0].bandwidth for x in s.actuators)
        f = np.zeros((n + m, n + m))
        f[:n, :n], f[:n, n:], f[n:, n:] = a, b, -np.eye(m) / tau
        g = np.vstack([np.zeros((n, m)), np.eye(m) / tau])
    else:
        f, g = a, b
    k_z = f.shape[0]
    big = expm(np.block([[f, g], [np.zeros((m, k_z + m))]]) / RATE)
    phi, gamma = big[:k_z, :k_z], big[:k_z, k_z:]
    ticks = np.arange(round(s.simulation.duration * RATE) + 1) / RATE
    z, xc, hold, pending = np.zeros(k_z), np.zeros(ctrl.states), np.zeros(m), np.zeros(m)
    ff = forces.command(ticks, ticks + 0.5 / RATE)
    out = np.empty((6, ticks.size))
    for k in range(ticks.size):
        out[:, k] = c_sig @ z[:n]
        xc, u = ctrl.step(xc, c_sens @ z[:n])
        hold, pending = (pending, u) if delay else (u, u)
        z = phi @ z + gamma @ np.clip(hold + ff[k], -limit, limit)
    return ticks, out


def test_the_compiled_loop_is_the_numpy_loop_on_the_mujoco_plant():
    """A 10 N pulse clipped at 8 N. Signals within 1e-4 of each one's peak: the linear plant leaves out terms of
    second order in the motion (the table turns ~2e-5 rad; the run's z, off by lever arm x angle^2, is 2e-5 of its
    peak off, ten times that at ten times the pulse); the central differences err by ~1e-10 (the loop on the
    casadi linearisation agrees with this one that closely), the compiled run's integration by ~1e-6 (the floor at
    a tenth of this pulse). A flipped delay is 1.5e-3 off, a loop without the actuators' lag 1.4e-2."""
    s = scenario_from_dict(geophone_data(max_force=8.0))
    ctrl, forces = dynamic(s), pulse(s, 10.0)
    run = Simulator(s).run(controller=ctrl, forces=forces)
    plant = mujoco_plant(s)
    ticks, ref = numpy_loop(s, plant, ctrl, forces)
    assert np.abs(run.actuator_forces).max() == pytest.approx(8.0)  # clipping binds
    scale = np.abs(ref).max(axis=1, keepdims=True)

    def error(other: np.ndarray) -> float:
        return float((np.abs(run.signals - other[:, ::2]).max(axis=1, keepdims=True) / scale).max())

    assert error(ref) < TOLERANCE, error(ref)
    times, ref_times = np.array([run.settling[k].time for k in SIGNALS]), settling(s, run, ticks, ref)
    np.testing.assert_allclose(times, ref_times, atol=1e-3)  # the 1 ms
    assert np.abs(times - ref_times).max() < 2e-5  # in fact ~1e-6 s; the wrong loops below settle ~0.45 ms off
    # the test can fail: a loop with the delay flipped, or without the lag, is far outside the tolerance
    for wrong in (numpy_loop(s, plant, ctrl, forces, delay=not ctrl.delay), numpy_loop(s, plant, ctrl, forces,
                                                                                        lag=False)):
        assert error(wrong[1]) > 10 * TOLERANCE, error(wrong[1])
        assert np.abs(settling(s, run, ticks, wrong[1]) - times).max() > 2e-4
