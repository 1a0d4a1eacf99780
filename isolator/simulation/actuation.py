"""Actuator force histories: forces files, saturation and the actuators' first-order lag.

A forces file (``docs/scenario-format.md``) is a CSV with a column ``t`` and
one column per actuator name, in N along the actuator's direction, linearly
interpolated in time and zero outside its time range. A time may appear twice
in a row to give a step: the first row holds the value just before it, the
second the value from it on (the simulation takes the side of each step that
its integration interval lies on). What acts on the table
is the command clipped at ``max_force`` and, for an actuator with a
``bandwidth``, passed through the first-order lag ``tau f' = u - f`` with
``tau = 1 / (2 pi bandwidth)`` (starting from zero force), solved exactly for
a command that is linear between evaluation times.

The table's RK4 steps take the lagged forces through
:func:`~isolator.simulation.lag_steps.lag_stages`: each of a step's four stages gets the force that makes the
step integrate the lag's exact force as it would a linear table's input, however fast the lag. So the table's
steps follow the table's own eigenvalues, not the lags' rates: a lag costs no extra step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from isolator.errors import ParameterError, ScenarioError
from isolator.numerics.rk4 import BY_TIME
from isolator.scenario.definitions import Scenario
from isolator.scenario.output_files import atomic_output
from isolator.scenario.tables import read_csv_columns
from isolator.simulation.lag_steps import clipped_stages
from isolator.simulation.time_grid import TimeGrid, stage_times

__all__ = ["LAG_WINDOW", "ForceHistory", "applied_forces", "lag_constants", "lag_sums", "lagged_actuators",
           "load_forces", "with_forces"]

#: the lags' sums run over windows of at most this many time constants (e^50: far from overflow; a sum's
#: rounding is relative to its largest term, which the window's end scales back to the force's size: the
#: step-by-step recursion's forces within 3e-13 of their peak)
LAG_WINDOW = 50.0


@dataclass(frozen=True)
class ForceHistory:
    """Commanded actuator forces over time.

    Attributes
    ----------
    t : ndarray (N,)
        Increasing times [s].
    forces : ndarray (n_actuators, N)
        [N] per scenario actuator, in the scenario's order (zero for actuators
        the source did not name).
    names : tuple of str
        The scenario's actuator names.
    """

    t: np.ndarray
    forces: np.ndarray
    names: tuple[str, ...]

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        f = np.asarray(self.forces, dtype=float).reshape(len(self.names), -1)
        if t.ndim != 1 or t.size != f.shape[1]:
            raise ParameterError(f"forces: {t.size} times for {f.shape[1]} force samples")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(f))):
            raise ParameterError("forces: times and forces must be finite (found NaN or infinity)")
        steps = np.diff(t)
        if t.size and (np.any(steps < 0) or np.any((steps[1:] == 0) & (steps[:-1] == 0))):
            raise ParameterError("forces.t: times must be increasing (a time at most twice, for a step)")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "forces", f)

    def command(self, times: np.ndarray, piece_time: np.ndarray | None = None) -> np.ndarray:
        """Commanded forces at ``times`` [N], shape ``(*times.shape, n_actuators)``; zero outside.

        At a step (a repeated time) the value is the one after it where
        ``piece_time`` (e.g. the middle of the integration interval) lies
        after ``times``, else the one before; without ``piece_time``, after.
        """
        times = np.asarray(times, dtype=float)
        out = np.zeros((*times.shape, len(self.names)))
        if self.t.size < 2:
            return out
        after = np.ones(times.shape, bool) if piece_time is None else np.asarray(piece_time) > times
        right = np.searchsorted(self.t, times, side="right") - 1
        left = np.searchsorted(self.t, times, side="left") - 1
        i = np.clip(np.where(after, right, left), 0, self.t.size - 2)
        t0, t1 = self.t[i], self.t[i + 1]
        w = np.where(t1 > t0, (times - t0) / np.where(t1 > t0, t1 - t0, 1.0), 1.0)
        inside = (times >= self.t[0]) & (times <= self.t[-1])
        for k in range(len(self.names)):
            f = self.forces[k]
            out[..., k] = np.where(inside, f[i] + w * (f[i + 1] - f[i]), 0.0)
        return out

    def to_csv(self, path: str | Path) -> Path:
        """Write the forces file (``t`` and one column per actuator) [s, N]."""
        path = Path(path)
        data = np.column_stack([self.t, self.forces.T])
        with atomic_output(path) as handle:
            handle.write(",".join(["t", *self.names]) + "\n")
            for row in data:
                handle.write(",".join(f"{v:.10g}" for v in row) + "\n")
        return path


def load_forces(path: str | Path, scenario: Scenario, key: str = "forces") -> ForceHistory:
    """Read a forces file for a scenario's actuators.

    The file has a column ``t`` (increasing; a time may appear twice in a row, for a step), at
    least two rows and one or more columns named after actuators; an actuator it does not name
    gets zero force.

    Raises
    ------
    ScenarioError
        No actuators in the scenario.
    ParameterError
        An unreadable, empty or non-UTF-8 file; a missing ``t`` column or one that names no
        actuator; no actuator named at all; fewer than two rows; a row of the wrong length;
        non-numeric or non-finite values; times not increasing. The message starts with ``key``
        and the file, then the line (and column).
    """
    names = tuple(a.name for a in scenario.actuators)
    if not names:
        raise ScenarioError(f"actuators: the scenario has no [[actuators]] to apply {key} with")
    try:
        columns = read_csv_columns(Path(path), key, ("t",), names, increasing="t", repeats=True)
    except ScenarioError as exc:  # the file is an argument, not scenario content
        raise ParameterError(str(exc)) from None
    t = columns.pop("t")
    if not columns:
        raise ParameterError(f"{key}: '{path}' names no actuator (give t and one or more of {', '.join(names)})")
    forces = np.array([columns.get(n, np.zeros_like(t)) for n in names])
    return ForceHistory(t, forces, names)


def applied_forces(
    scenario: Scenario, command: np.ndarray, times: np.ndarray, initial: np.ndarray | None = None
) -> np.ndarray:
    """What the actuators apply for a command: clipped at ``max_force``, then lagged.

    Parameters
    ----------
    scenario : Scenario
    command : ndarray (N, n_actuators)
        Commanded forces [N] at ``times``.
    times : ndarray (N,)
        Non-decreasing times [s] (repeated times allowed).
    initial : ndarray (n_actuators,), optional
        The lagged actuators' force at ``times[0]`` [N] (default zero).

    Returns
    -------
    ndarray (N, n_actuators)
        [N]
    """
    limits = np.array([a.max_force for a in scenario.actuators])
    u = np.clip(command, -limits, limits)
    out = u.copy()
    lagged = lagged_actuators(scenario)
    if not lagged:
        return out
    tau = lag_constants(scenario)[lagged]
    times = np.asarray(times, dtype=float)
    # exact for u linear over [t_i, t_i+1] (held where the time repeats): y_i+1 = d_i y_i + c_i with
    # d = e^(-h/tau), c = u_i+1 (1 - a) - u_i (d - a), a = tau (1 - d) / h (a few step lengths h: their
    # coefficients once); summed in windows of at most LAG_WINDOW time constants as
    # z_n = y_n e^((t_n - r) / tau) = z_0 + sum c_k e^((t_k+1 - r) / tau)
    lengths, which = np.unique(np.diff(times), return_inverse=True)
    held = lengths[:, None] <= 0
    safe = np.where(held, 1.0, lengths[:, None])
    d = np.exp(-safe / tau[None, :])
    a = tau[None, :] * (1 - d) / safe
    ahead, behind = np.where(held, 0.0, 1 - a), np.where(held, 0.0, d - a)
    ul = u[:, lagged]
    c = ul[1:] * ahead[which] - ul[:-1] * behind[which]
    y = np.zeros(len(lagged)) if initial is None else np.asarray(initial, dtype=float)[lagged]
    lags = lag_sums(times, c, y, tau)
    out[:, lagged] = lags
    return out


def lagged_actuators(scenario: Scenario) -> list[int]:
    """The indices of the scenario's actuators with a ``bandwidth`` (a first-order lag)."""
    return [k for k, a in enumerate(scenario.actuators) if a.bandwidth is not None]


def lag_constants(scenario: Scenario) -> np.ndarray:
    """Each actuator's lag time constant ``1 / (2 pi bandwidth)`` [s] (1 for one without a lag)."""
    return np.array([1.0 / (2 * math.pi * a.bandwidth) if a.bandwidth is not None else 1.0
                     for a in scenario.actuators])


def lag_sums(times: np.ndarray, c: np.ndarray, y0: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """The lags' forces at ``times`` (N,) [s] from ``y0`` (lags,) [N] by ``y_i+1 = e^(-(t_i+1 - t_i)/tau) y_i + c_i``
    (``c`` (N - 1, lags) [N]): summed in windows of at most :data:`LAG_WINDOW` time constants as
    ``z_n = y_n e^((t_n - r) / tau) = z_0 + sum c_k e^((t_k+1 - r) / tau)``."""
    lags = np.empty((times.size, tau.size))
    lags[0] = y0
    edges = np.searchsorted(times, times[0] + LAG_WINDOW * tau.min() * np.arange(1, 2 + (times[-1] - times[0]) / (
        LAG_WINDOW * tau.min())), side="right")
    first = 0
    for last in np.unique(np.minimum(edges, times.size - 1)):
        if last <= first:
            continue
        grow = np.exp((times[first + 1 : last + 1, None] - times[first]) / tau[None, :])
        lags[first + 1 : last + 1] = (lags[first] + np.cumsum(c[first:last] * grow, axis=0)) / grow
        first = last
    return lags


def with_forces(
    scenario: Scenario, where: slice, grid: TimeGrid, inputs: np.ndarray, substeps: int, forces: ForceHistory | None
) -> tuple[np.ndarray, np.ndarray]:
    """The model's inputs with the actuators' forces in their ``where`` slot: what the RK4 steps take, and what
    the actuators apply at every RK4 stage time.

    Returns
    -------
    taken : ndarray (intervals, stages, input size)
        The steps' inputs: at the stage times (``2 substeps + 1``) when no actuator lags, else four per step
        (:func:`~isolator.numerics.rk4.stage_count` with ``split``), a lagged force as
        :func:`~isolator.simulation.lag_steps.lag_stages` gives it to each stage.
    applied : ndarray (intervals, 2 substeps + 1, input size)
        At the stage times, the forces applied there [N].

    Raises
    ------
    ParameterError
        ``forces`` is for other actuators than the scenario's.
    """
    if forces is None:
        return inputs, inputs
    names = tuple(a.name for a in scenario.actuators)
    if forces.names != names:
        raise ParameterError(f"forces: are for actuators {forces.names}, the scenario has {names}")
    times, mid = stage_times(grid, substeps)
    command = forces.command(times.ravel(), mid.ravel()).reshape(*times.shape, len(names))
    limits = np.array([a.max_force for a in scenario.actuators])
    applied = np.clip(command, -limits, limits)
    out = inputs.copy()
    lagged = lagged_actuators(scenario)
    if not lagged:
        out[..., where] = applied
        return out, out
    # the lags step by step, their kinks where the command crosses its limits followed exactly: the force at each
    # step's start by the recursion (the step's own part, from zero force, is lag_stages' end), then the stages
    raw, tau, limit = command[..., lagged], lag_constants(scenario)[lagged], limits[lagged]
    lengths, which = np.unique(np.diff(grid.nodes) / substeps, return_inverse=True)
    at = np.arange(0, 2 * substeps, 2)  # each step's start among the stage times
    # (the lag is linear: its part from zero force, plus the start's force times a unit's)
    own, unit = clipped_stages(raw[:, at], raw[:, at + 1], raw[:, at + 2], lengths, which, tau, limit)
    starts = np.append(times[:, at].ravel(), times[-1, -1])
    lags = lag_sums(starts, np.reshape(own[5], (-1, len(lagged))), np.zeros(len(lagged)), tau)
    first = lags[:-1].reshape(own[5].shape)
    stages = [a + first * b for a, b in zip(own[:4], unit[:4], strict=True)]
    half, end = (a + first * b for a, b in zip(own[4:], unit[4:], strict=True))
    applied[:, at[:, None], lagged] = first
    applied[:, at[:, None] + 1, lagged] = half
    applied[:, -1, lagged] = end[:, -1]
    out[..., where] = applied
    taken = out[:, (at[:, None] + np.array(BY_TIME)[None, :]).ravel()]  # (intervals, 4 substeps, input size)
    slots = np.arange(where.start, where.stop)[lagged]
    taken[..., slots] = np.stack(stages, axis=2).reshape(times.shape[0], 4 * substeps, len(lagged))
    return taken, out
