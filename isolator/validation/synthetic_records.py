"""Synthetic measured records from the independent MuJoCo check: what a calibration is tested on.

A "true" table (a scenario with the isolators the records should reveal) is simulated in MuJoCo
(:class:`~isolator.validation.multibody.MujocoTable`, which shares nothing with the casadi model but the
scenario) and its sensors are read from MuJoCo's states with their own kinematics, written here in numpy:
a table point's world position ``c + R r``, velocity ``v + w x R r`` and acceleration
``a + alpha x R r + w x (w x R r)`` with MuJoCo's accelerations. Then white noise of a given fraction of
each channel's RMS is added (seeded).

- :func:`move_record`: the carriages move as the scenario says, the floor still.
- :func:`floor_record`: the carriages parked, the floor moving along x, y, z with a random-phase multisine
  (flat acceleration spectrum between two frequencies), read by the floor sensors.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from isolator.scenario.definitions import Scenario, SimulationSettings
from isolator.scenario.sensors import Sensor
from isolator.validation.multibody import MujocoTable
from isolator.validation.piecewise import solve_piecewise

__all__ = ["FloorMotion", "SyntheticRecord", "add_noise", "floor_record", "move_record"]


@dataclass(frozen=True)
class SyntheticRecord:
    """Noise-free sensor signals from the MuJoCo check.

    Attributes
    ----------
    t : ndarray (N,)
        [s]
    channels : dict of str to ndarray (N,)
        By sensor name, in its SI quantity.
    """

    t: np.ndarray
    channels: dict[str, np.ndarray]

    def noisy(self, fraction: float, seed: int) -> SyntheticRecord:
        """With white noise of ``fraction`` of each channel's RMS added (seeded)."""
        return SyntheticRecord(self.t, add_noise(self.channels, fraction, seed))

    def write_csv(self, path: str | Path, comment: str = "") -> Path:
        """Write ``t`` and the channels as CSV (values to 10 significant digits)."""
        path = Path(path)
        names = list(self.channels)
        data = np.column_stack([self.t, *[self.channels[n] for n in names]])
        with open(path, "w") as handle:
            handle.write(",".join(["t", *names]) + "\n")
            np.savetxt(handle, data, delimiter=",", fmt="%.10g")
        return path


def add_noise(channels: dict[str, np.ndarray], fraction: float, seed: int) -> dict[str, np.ndarray]:
    """Each channel plus white noise of RMS ``fraction`` times the channel's RMS."""
    rng = np.random.default_rng(seed)
    return {n: v + fraction * float(np.sqrt(np.mean(v**2))) * rng.standard_normal(v.size) for n, v in channels.items()}


@dataclass(frozen=True)
class FloorMotion:
    """A random-phase multisine floor translation along x, y, z [m]: ``sum A cos(w t + phi)`` per axis with
    a flat acceleration amplitude between ``low`` and ``high`` [Hz] (``count`` components per axis, RMS
    acceleration ``rms`` [m/s^2] per axis)."""

    low: float = 0.5
    high: float = 40.0
    count: int = 400
    rms: float = 0.01
    seed: int = 0
    axes: str = "xyz"

    def components(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        rng = np.random.default_rng(self.seed)
        w = 2 * np.pi * rng.uniform(self.low, self.high, size=(3, self.count))
        phase = rng.uniform(0, 2 * np.pi, size=(3, self.count))
        amp = self.rms * np.sqrt(2.0 / self.count) / w**2  # acceleration amplitude rms*sqrt(2/count) per line
        amp[[k for k, a in enumerate("xyz") if a not in self.axes]] = 0.0
        return w, phase, amp

    def at(self, t: np.ndarray | float) -> np.ndarray:
        """Translation, velocity and acceleration (3, 3, N) at times ``t`` [s]."""
        w, phase, amp = self.components()
        t = np.atleast_1d(np.asarray(t, dtype=float))
        arg = w[:, :, None] * t[None, None, :] + phase[:, :, None]
        c, s = np.cos(arg), np.sin(arg)
        return np.array([np.sum(amp[:, :, None] * c, axis=1), -np.sum((amp * w)[:, :, None] * s, axis=1),
                         -np.sum((amp * w**2)[:, :, None] * c, axis=1)])


def _read(table: MujocoTable, sensors: tuple[Sensor, ...], t: np.ndarray, states: np.ndarray, accelerations: np.ndarray,
          ground: np.ndarray | None) -> dict[str, np.ndarray]:
    """Sensor signals from MuJoCo's states (N, 13: position, quaternion, world velocity, table-frame angular
    velocity) and accelerations (N, 6: world linear, table-frame angular)."""
    q = states[:, 3:7] / np.linalg.norm(states[:, 3:7], axis=1, keepdims=True)
    w_, x_, y_, z_ = q.T
    rot = np.moveaxis(np.array([
        [1 - 2 * (y_ * y_ + z_ * z_), 2 * (x_ * y_ - w_ * z_), 2 * (x_ * z_ + w_ * y_)],
        [2 * (x_ * y_ + w_ * z_), 1 - 2 * (x_ * x_ + z_ * z_), 2 * (y_ * z_ - w_ * x_)],
        [2 * (x_ * z_ - w_ * y_), 2 * (y_ * z_ + w_ * x_), 1 - 2 * (x_ * x_ + y_ * y_)]]), 2, 0)
    omega = np.einsum("nij,nj->ni", rot, states[:, 10:13])
    alpha = np.einsum("nij,nj->ni", rot, accelerations[:, 3:6])  # d(R w_b)/dt = R w_b' (w x w = 0)
    out = {}
    for s in sensors:
        n = np.asarray(s.direction, dtype=float)
        if s.on == "floor":
            out[s.name] = np.zeros(t.size) if ground is None else n @ ground[s.order]
            continue
        arm = np.einsum("nij,j->ni", rot, np.asarray(s.position, dtype=float))
        if s.order == 0:
            signal = states[:, 0:3] + arm - (states[0, 0:3] + arm[0])
        elif s.order == 1:
            signal = states[:, 7:10] + np.cross(omega, arm)
        else:
            signal = accelerations[:, 0:3] + np.cross(alpha, arm) + np.cross(omega, np.cross(omega, arm))
        out[s.name] = signal @ n
    return out


def move_record(scenario: Scenario, duration: float, rate: float, rtol: float = 1e-10) -> SyntheticRecord:
    """The scenario's move in MuJoCo, its ``[[sensors]]`` read at ``rate`` [Hz] from 0 to ``duration`` [s]."""
    scenario = replace(scenario, simulation=SimulationSettings(duration=duration, sample_rate=rate))
    table = MujocoTable(scenario)
    run = table.simulate(rtol=rtol, atol=1e-14)
    acc = np.array([table.accelerations(y, table._carriages(t, t), t) for t, y in zip(run.t, run.states, strict=True)])
    return SyntheticRecord(run.t, _read(table, scenario.sensors, run.t, run.states, acc, None))


def floor_record(scenario: Scenario, motion: FloorMotion, duration: float, rate: float, rtol: float = 1e-9
                 ) -> SyntheticRecord:
    """The table on a moving floor in MuJoCo (carriages parked at their start), its ``[[sensors]]`` read at
    ``rate`` [Hz] from 0 to ``duration`` [s]; the table starts at rest (its first seconds are a transient a
    calibration's spectra average over)."""
    table = MujocoTable(scenario)
    parked = np.zeros((3, len(scenario.carriages)))
    parked[0] = scenario.initial_positions()

    def ground(t: float) -> np.ndarray:
        g = motion.at(t)[:, :, 0]
        return np.r_[g[0], np.zeros(3), g[1], np.zeros(3)]

    def rhs(t: float, y: np.ndarray, _: float) -> np.ndarray:
        acc = table.accelerations(y, parked, t, ground(t))
        qw, qx, qy, qz = y[3:7]
        p, q, r = y[10:13]
        qdot = 0.5 * np.array([-qx * p - qy * q - qz * r, qw * p + qy * r - qz * q, qw * q + qz * p - qx * r,
                               qw * r + qx * q - qy * p])
        return np.concatenate([y[7:10], qdot, acc])

    t = np.arange(round(duration * rate) + 1) / rate
    y0 = table.equilibrium(parked[0])
    states = solve_piecewise(rhs, y0, t, (), rtol=rtol, atol=1e-13, max_step=0.25 / motion.high)
    acc = np.array([table.accelerations(y, parked, ti, ground(ti)) for ti, y in zip(t, states, strict=True)])
    return SyntheticRecord(t, _read(table, scenario.sensors, t, states, acc, motion.at(t)))
