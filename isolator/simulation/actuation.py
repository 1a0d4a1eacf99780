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

The table's RK4 steps take the lagged forces through :func:`lag_stages`: the force each of a step's four
stages sees is chosen so that the step integrates the lag's exact force as a linear table would its input,
through the step's third power of the table's matrix (the moments of the force against ``(h - s)^n / n!``,
n = 0..3, exact), however fast the lag. So the table's steps follow the table's own eigenvalues, not the
lags' rates: a lag costs no extra step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np

from isolator.errors import ParameterError, ScenarioError
from isolator.numerics.rk4 import BY_TIME
from isolator.scenario.definitions import Scenario
from isolator.scenario.output_files import atomic_output
from isolator.scenario.tables import read_csv_columns
from isolator.simulation.time_grid import TimeGrid, stage_times

__all__ = ["LAG_WINDOW", "ForceHistory", "applied_forces", "lag_constants", "lag_stages", "lag_sums",
           "lag_step", "lagged_actuators", "load_forces", "with_forces"]

#: the lags' sums run over windows of at most this many time constants (e^50: far from overflow; a sum's
#: rounding is relative to its largest term, which the window's end scales back to the force's size: the
#: step-by-step recursion's forces within 3e-13 of their peak)
LAG_WINDOW = 50.0


#: below this ``|z|`` the exponential's moments come down from the series of the fifth (16 terms: within 1e-16),
#: above it up from the first (which divides by ``z``)
_SERIES_BELOW = 1.0
_TERMS = 16


def _exponential_moments(z: Any, exp: Any, select: Any) -> tuple[list[Any], list[Any]]:
    """``g_k = int_0^1 th^k e^(z th) dth`` and ``q_k = (g_k - 1/(k+1)) / z = (g_0 - g_(k+1)) / (k+1)``,
    k = 0..3, for ``z <= 0``: each recursion ``z g_k = e^z - k g_(k-1)`` in its stable direction."""
    small = z > -_SERIES_BELOW
    safe = select(small, -1.0, z)  # the upward branch, never at z = 0
    ez, e_small = exp(safe), exp(z)
    term, down = 1.0, 1.0 / 5
    for m in range(1, _TERMS):
        term = term * z / m
        down = down + term / (m + 5)
    downward = [down]
    for k in range(4, 0, -1):
        downward.insert(0, (e_small - z * downward[0]) / k)
    upward = [(ez - 1.0) / safe]
    for k in range(1, 5):
        upward.append((ez - k * upward[-1]) / safe)
    g = [select(small, a, b) for a, b in zip(downward, upward, strict=True)]
    return g[:4], [(g[0] - g[k + 1]) / (k + 1) for k in range(4)]


def _pieces(u0: Any, um: Any, u1: Any, limit: Any, lo: Any, hi: Any) -> list[tuple[Any, Any, Any, Any]]:
    """The command over a step as linear pieces ``(start, length, value at start, value at end)`` in units of the
    step: its two halves, each cut where it crosses ``+-limit`` and clipped there (None: not clipped)."""
    if limit is None:
        return [(0.0, 0.5, u0, um), (0.5, 0.5, um, u1)]
    out = []
    for start, ua, ub in ((0.0, u0, um), (0.5, um, u1)):
        slope = ub - ua
        safe = select_nonzero(slope)
        cuts = [lo(hi((sign * limit - ua) / safe, 0.0), 1.0) for sign in (1.0, -1.0)]
        marks = [0.0, lo(cuts[0], cuts[1]), hi(cuts[0], cuts[1]), 1.0]
        values = [lo(hi(ua + slope * m, -limit), limit) for m in marks]
        out += [(start + marks[i] / 2, (marks[i + 1] - marks[i]) / 2, values[i], values[i + 1]) for i in range(3)]
    return out


def select_nonzero(x: Any) -> Any:
    """``x``, or 1 where it is 0 (a divisor whose quotient is then not used)."""
    return ca.if_else(x == 0, 1.0, x) if isinstance(x, (ca.SX, ca.MX)) else np.where(x == 0, 1.0, x)


def lag_stages(f0: Any, u0: Any, um: Any, u1: Any, h: Any, tau: Any, limit: Any = None
               ) -> tuple[list[Any], list[Any]]:
    """The forces an RK4 step of length ``h`` gives its four stages for a lagged actuator, and the lag's force at
    the step's middle and end.

    The command [N] is ``u0``, ``um``, ``u1`` at the step's start, middle and end and linear between them,
    clipped at ``+-limit`` (its kinks where it crosses them, inside the step, followed exactly); the lag
    ``tau f' = u - f`` starts from ``f0`` [N]. The stage forces ``b1..b4`` are those whose RK4 step of a linear
    system ``x' = A x + B f`` equals the exact one through ``h^3 A^3``: the moments
    ``int_0^h (h - s)^n / n! f(s) ds``, n = 0..3, of the lag's exact force equal RK4's
    ``h/6 (b1 + 2 b2 + 2 b3 + b4)``, ``h^2/6 (b1 + b2 + b3)``, ``h^3/12 (b1 + b2)``, ``h^4/24 b1`` (a constant
    force gives its value to every stage; a fast lag's transient, its weight in the step).

    Parameters
    ----------
    f0, u0, um, u1 : float, ndarray or casadi expression
        [N], broadcast together.
    h, tau : float, ndarray or casadi expression
        The step and the lag's time constant [s], ``h > 0``, ``tau > 0``.
    limit : float, ndarray or casadi expression, optional
        The actuator's ``max_force`` [N] (None: the command as it is).

    Returns
    -------
    stages : list
        ``[b1, b2, b3, b4]`` [N].
    forces : list
        The lag's exact force at ``h / 2`` and ``h`` [N].
    """
    symbolic = any(isinstance(v, (ca.SX, ca.MX)) for v in (f0, u0, um, u1, h, tau, limit))
    exp, select, lo, hi = (ca.exp, ca.if_else, ca.fmin, ca.fmax) if symbolic else (
        np.exp, np.where, np.minimum, np.maximum)
    moments: list[Any] = [0.0] * 4
    ends, fa = [], f0
    # each piece: the moments of f(a + w) against w^k over its length l, in units of l^(k+1), shifted to
    # (1 - a - w)^n / n! (units of the step)
    for start, length, ua, ub in _pieces(u0, um, u1, limit, lo, hi):
        z = -length * h / tau
        g, q = _exponential_moments(z, exp, select)
        mu = [ua / (k + 1) + (ub - ua) / (k + 2) + (fa - ua) * g[k] - (ub - ua) * q[k] for k in range(4)]
        scaled = [length ** (k + 1) * mu[k] for k in range(4)]
        for n in range(4):
            moments[n] = moments[n] + sum(math.comb(n, k) * (1 - start) ** (n - k) * (-1) ** k * scaled[k]
                                          for k in range(n + 1)) / math.factorial(n)
        fa = ub + (fa - ua) * exp(z) - (ub - ua) * g[0]
        ends.append(fa)
    b1 = 24 * moments[3]
    b2 = 12 * moments[2] - b1
    b3 = 6 * moments[1] - b1 - b2
    b4 = 6 * moments[0] - b1 - 2 * b2 - 2 * b3
    return [b1, b2, b3, b4], [ends[len(ends) // 2 - 1], ends[-1]]


def lag_step(tau: Sequence[float], limit: Sequence[float]) -> ca.Function:
    """``(f0, u0, um, u1, h) -> (lags, 6)``: :func:`lag_stages` of lags with time constants ``tau`` [s] and limits
    ``limit`` [N] (columns ``b1..b4``, the middle and end forces), as a casadi function that follows the
    clipping's kinks only in a step where some lag's command crosses its limit (a conditional call: the other
    branch, the two halves of the clipped command, is not evaluated)."""
    n = len(tau)
    f0, u0, um, u1 = (ca.SX.sym(name, n) for name in ("f0", "u0", "um", "u1"))
    h = ca.SX.sym("h")
    lim = ca.DM(list(limit))
    clipped = [ca.fmin(ca.fmax(u, -lim), lim) for u in (u0, um, u1)]
    args = [f0, u0, um, u1, h]

    # within the limits, linear: (b1..b4, f_half, f_end) = W (f0, u0, um, u1), one W per time constant
    unit = ca.SX.sym("unit", 4)
    weights = {t: ca.densify(ca.jacobian(ca.vertcat(*sum(lag_stages(*ca.vertsplit(unit), h, t), [])), unit))
               for t in set(tau)}
    plain = ca.Function("lag_plain", args, [ca.vertcat(*[(weights[tau[k]] @ ca.vertcat(
        f0[k], clipped[0][k], clipped[1][k], clipped[2][k])).T for k in range(n)])], {"cse": True})
    cut = ca.Function("lag_cut", args, [ca.vertcat(*[ca.horzcat(*sum(lag_stages(
        f0[k], u0[k], um[k], u1[k], h, tau[k], limit[k]), [])) for k in range(n)])], {"cse": True})
    side = [ca.sign(ca.fmax(u - lim, 0.0)) - ca.sign(ca.fmax(-lim - u, 0.0)) for u in (u0, um, u1)]
    crossing = ca.Function("lag_crossing", [u0, um, u1], [ca.sum1((side[0] != side[1]) + (side[1] != side[2])) > 0])
    switch = ca.Function.conditional("lag_switch", [plain], cut)
    mx = [ca.MX.sym(name, n) for name in ("f0", "u0", "um", "u1")] + [ca.MX.sym("h")]
    return ca.Function("lag_step", mx, [switch(crossing(*mx[1:4]), *mx)])


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
        (:func:`~isolator.numerics.rk4.stage_count` with ``split``), a lagged force as :func:`lag_stages` gives
        it to each stage.
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
    h = (np.diff(grid.nodes) / substeps)[:, None, None]
    at = np.arange(0, 2 * substeps, 2)  # each step's start among the stage times
    ramps = (raw[:, at], raw[:, at + 1], raw[:, at + 2], h, tau, limit)
    _, (_, own) = lag_stages(0.0, *ramps)
    starts = np.append(times[:, at].ravel(), times[-1, -1])
    lags = lag_sums(starts, np.reshape(own, (-1, len(lagged))), np.zeros(len(lagged)), tau)
    stages, (half, end) = lag_stages(lags[:-1].reshape(own.shape), *ramps)
    applied[:, at[:, None], lagged] = lags[:-1].reshape(own.shape)
    applied[:, at[:, None] + 1, lagged] = half
    applied[:, -1, lagged] = end[:, -1]
    out[..., where] = applied
    taken = out[:, (at[:, None] + np.array(BY_TIME)[None, :]).ravel()]  # (intervals, 4 substeps, input size)
    slots = np.arange(where.start, where.stop)[lagged]
    taken[..., slots] = np.stack(stages, axis=2).reshape(times.shape[0], 4 * substeps, len(lagged))
    return taken, out
