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
from functools import cached_property
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from isolator.scenario.definitions import Scenario, SimulationSettings
from isolator.scenario.output_files import atomic_output
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
        with atomic_output(path) as handle:
            handle.write(",".join(["t", *names]) + "\n")
            np.savetxt(handle, data, delimiter=",", fmt="%.10g")
        return path


def add_noise(channels: dict[str, np.ndarray], fraction: float, seed: int) -> dict[str, np.ndarray]:
    """Each channel plus white noise of RMS ``fraction`` times the channel's RMS."""
    rng = np.random.default_rng(seed)
    return {n: v + fraction * float(np.sqrt(np.mean(v**2))) * rng.standard_normal(v.size) for n, v in channels.items()}


@dataclass(frozen=True)
class FloorMotion:
    """A random floor translation along x, y, z [m]: on every frequency ``k / period`` between ``low`` and
    ``high`` [Hz] a line of the same acceleration amplitude and a random phase per axis (a periodic,
    band-limited random signal; RMS acceleration ``rms`` [m/s^2] per moving axis), sampled at 64 ``high`` and
    interpolated by a cubic spline whose derivatives are the velocity and acceleration (one consistent
    motion for MuJoCo's anchors and the floor sensors)."""

    low: float = 0.5
    high: float = 40.0
    rms: float = 0.01
    seed: int = 0
    axes: str = "xyz"
    period: float = 64.0

    @cached_property
    def _spline(self) -> CubicSpline:
        rng = np.random.default_rng(self.seed)
        rate = 64.0 * self.high  # the spline's acceleration within (w h)^2 / 12 < 1e-3 of the band-limited one
        n = round(self.period * rate)
        f = np.fft.rfftfreq(n, 1.0 / rate)
        lines = (f >= self.low) & (f <= self.high)
        spectrum = np.zeros((3, f.size), dtype=complex)
        for k, axis in enumerate("xyz"):
            if axis in self.axes:
                phases = rng.uniform(size=int(lines.sum()))
                spectrum[k, lines] = np.exp(2j * np.pi * phases) / (2 * np.pi * f[lines]) ** 2
        disp = np.fft.irfft(spectrum, n, axis=1)
        acc = np.fft.irfft(spectrum * -(2 * np.pi * f) ** 2, n, axis=1)
        scale = np.array([self.rms / np.sqrt(np.mean(a**2)) if np.any(a) else 0.0 for a in acc])
        t = np.arange(n + 1) / rate
        values = np.concatenate([disp, disp[:, :1]], axis=1) * scale[:, None]
        return CubicSpline(t, values, axis=1, bc_type="periodic")

    def at(self, t: np.ndarray | float) -> np.ndarray:
        """Translation, velocity and acceleration (3, 3, N) at times ``t`` [s]."""
        t = np.mod(np.atleast_1d(np.asarray(t, dtype=float)), self.period)
        spline = self._spline
        return np.array([spline(t), spline(t, 1), spline(t, 2)])


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


def floor_record(scenario: Scenario, motion: FloorMotion, duration: float, rate: float, rtol: float = 1e-9,
                 settle: float = 10.0) -> SyntheticRecord:
    """The table on a moving floor in MuJoCo (carriages parked at their start), its ``[[sensors]]`` read at
    ``rate`` [Hz] for ``duration`` [s]. The floor has moved for ``settle`` [s] before the record starts (the
    table starts at rest; a measured table has long been moving with its floor), the record's time from 0."""
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
    run = np.r_[0.0, settle + t] if settle > 0 else t
    states = solve_piecewise(rhs, y0, run, (), rtol=rtol, atol=1e-13, max_step=0.25 / motion.high)
    states = states[1:] if settle > 0 else states
    acc = np.array([table.accelerations(y, parked, ti, ground(ti)) for ti, y in zip(settle + t, states, strict=True)])
    channels = _read(table, scenario.sensors, t, states, acc, motion.at(settle + t))
    table_sensors = [s.name for s in scenario.sensors if s.on == "table" and s.order == 0]
    for name in table_sensors:  # displacements from the table's rest, not from where the record starts
        channels[name] = channels[name] + _rest_offset(table, scenario, states[0], y0, name)
    return SyntheticRecord(t, channels)


def _rest_offset(table: MujocoTable, scenario: Scenario, first: np.ndarray, rest: np.ndarray, name: str) -> float:
    """A displacement sensor's reading at the record's first state, measured from the rest state."""
    sensor = next(s for s in scenario.sensors if s.name == name)
    both = np.vstack([rest, first])
    reading = _read(table, (sensor,), np.zeros(2), both, np.zeros((2, 6)), None)[name]
    return float(reading[1])
