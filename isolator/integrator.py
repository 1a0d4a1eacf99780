"""Fixed-grid Runge-Kutta integration of a model, compiled, restarted at breakpoints.

The time grid is the union of the output sample times and the profiles'
breakpoints, so no step straddles a jump in a carriage's acceleration. Each
grid interval is split into ``substeps`` classical RK4 steps; the carriages'
coordinates are evaluated (in numpy) at every stage time with the polynomial
piece of the interval, i.e. one-sided at breakpoints. The stepping loop runs
in compiled code, in chunks of a fixed number of intervals.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property, lru_cache

import casadi as ca
import numpy as np

from .model import Model, ParameterLayout, quaternion_to_matrix
from .native import NativeFunction
from .scenario import Scenario, SimulationSettings

__all__ = [
    "Stepper",
    "TimeGrid",
    "grid_breakpoints",
    "inputs_at",
    "model_inputs",
    "sensed_motion",
    "signal_function",
    "stage_times",
    "time_grid",
]

CHUNK = 512
#: terms of the atan series in :func:`sensed_motion` (t^0 ... t^14)
ATAN_TERMS = 8


@dataclass(frozen=True)
class TimeGrid:
    """Integration grid.

    Attributes
    ----------
    nodes : ndarray
        Grid times [s], increasing, from 0 to the duration.
    is_sample : ndarray of bool
        Which nodes are output samples.
    """

    nodes: np.ndarray
    is_sample: np.ndarray

    @cached_property
    def samples(self) -> np.ndarray:
        """The output sample times [s] (computed once)."""
        return self.nodes[self.is_sample]


def grid_breakpoints(settings: SimulationSettings, breakpoints: tuple[float, ...]) -> np.ndarray:
    """Breakpoints inside the run as the integration grid holds them [s], sorted, unique.

    A breakpoint within round-off (1e-9 relative) of an output sample takes
    that sample's time, so that every tool that steps at breakpoints (the
    grid, forces files that step there) agrees on the instant.
    """
    samples = settings.sample_times()
    inside = np.array([b for b in breakpoints if 0.0 < b < samples[-1]], dtype=float)
    if inside.size:
        index = np.clip(np.rint(inside * settings.sample_rate).astype(int), 0, samples.size - 1)
        nearest = samples[index]
        inside = np.where(np.abs(nearest - inside) <= 1e-9 * np.maximum(1.0, inside), nearest, inside)
    return np.unique(inside)


def time_grid(settings: SimulationSettings, breakpoints: tuple[float, ...]) -> TimeGrid:
    """The settings' output samples merged with breakpoints [s]."""
    samples = settings.sample_times()
    extra = grid_breakpoints(settings, breakpoints)
    extra = extra[~np.isin(extra, samples)]
    nodes = np.concatenate([samples, extra])
    flags = np.concatenate([np.ones(samples.size, bool), np.zeros(extra.size, bool)])
    order = np.argsort(nodes, kind="stable")
    return TimeGrid(nodes[order], flags[order])


def stage_times(grid: TimeGrid, substeps: int) -> tuple[np.ndarray, np.ndarray]:
    """RK4 stage times of every grid interval and each interval's midpoint [s].

    Returns
    -------
    times, mid : ndarray, shape (intervals, 2 substeps + 1)
        Non-decreasing when flattened in C order.
    """
    t0, t1 = grid.nodes[:-1], grid.nodes[1:]
    frac = np.arange(2 * substeps + 1) / (2 * substeps)
    times = t0[:, None] + (t1 - t0)[:, None] * frac[None, :]
    mid = np.broadcast_to(((t0 + t1) / 2)[:, None], times.shape)
    return times, mid


def model_inputs(scenario: Scenario, grid: TimeGrid, substeps: int) -> np.ndarray:
    """The model's inputs ``u`` at every RK stage time of every grid interval.

    Returns
    -------
    ndarray, shape (intervals, 2 substeps + 1, input size)
        One-sided within each interval: the profile piece is chosen by the
        interval's midpoint.
    """
    return inputs_at(scenario, *stage_times(grid, substeps))


def inputs_at(scenario: Scenario, times: np.ndarray, mid: np.ndarray) -> np.ndarray:
    """The model's inputs ``u`` at ``times`` [s], each on the profile piece that holds ``mid`` [s].

    Carriage (q, q', q''), then the floor's motion when the scenario has some,
    then zero actuator forces (see :class:`isolator.model.ParameterLayout`).

    Returns
    -------
    ndarray, shape (*times.shape, input size)
    """
    n = len(scenario.carriages)
    layout = ParameterLayout.of(scenario)
    out = np.zeros((*times.shape, layout.input_size))
    for i, carriage in enumerate(scenario.carriages):
        q, v, a = carriage.profile.evaluate(times, mid)
        out[..., i] = q
        out[..., n + i] = v
        out[..., 2 * n + i] = a
    if layout.ground and scenario.ground is not None:
        out[..., layout.ground_slice] = scenario.ground.displacement(times, mid)
    return out


def sensed_motion(kind: str, x: ca.MX | ca.SX, reference: ca.MX | ca.SX) -> ca.MX | ca.SX:
    """The table's motion as ideal inertial sensors report it, (12,).

    Displacement of the mass centre [m] and rotation vector of ``R R_ref^T``
    [rad] from the state ``reference``, then velocity [m/s] and angular
    velocity [rad/s], world axes. The paper model: its coordinates and rates.

    The rotation vector of the relative quaternion ``(w, v)`` is
    ``2 atan(|v|/|w|)/|v| sign(w) v``, written as ``2 v/w`` times the series
    of ``atan(t)/t`` in ``t^2 = |v|^2/w^2`` to ``t^14``: exact to rounding
    (relative error below 1e-15) for rotations up to 0.2 rad, the most a run
    may turn before it is reported as diverged (see
    :func:`isolator.simulation.relative_rotation_vector` for any angle). It is
    a few times cheaper than ``atan2``, needs no normalisation (it does not
    change when either quaternion is scaled) and is smooth at zero.
    """
    if kind != "exact":
        return ca.vertcat(x[:6] - reference[:6], x[6:12])
    q, r = x[3:7], reference[3:7]
    w0, v0 = r[0], -r[1:4]
    w, v = q[0], q[1:4]
    rel_w = w * w0 - ca.dot(v, v0)
    rel_v = w * v0 + w0 * v + ca.cross(v, v0)
    inverse = 1 / rel_w
    t2 = ca.dot(rel_v, rel_v) * inverse * inverse
    series = 0.0
    for k in range(ATAN_TERMS - 1, -1, -1):  # atan(t)/t = 1 - t^2/3 + t^4/5 - ...
        series = (-1) ** k / (2 * k + 1) + t2 * series
    angles = 2 * inverse * series * rel_v
    omega_world = quaternion_to_matrix(x[3:7]) @ x[10:13]
    return ca.vertcat(x[0:3] - reference[0:3], angles, x[7:10], omega_world)


@lru_cache(maxsize=8)
def signal_function(kind: str, n_states: int) -> ca.Function:
    """``(x, reference) -> (6,)``: the six table signals of a state (the first half of
    :func:`sensed_motion`), scalar code."""
    x, reference = ca.SX.sym("x", n_states), ca.SX.sym("x_ref", n_states)
    return ca.Function("table_signals", [x, reference], [sensed_motion(kind, x, reference)[:6]])


class Stepper:
    """Compiled RK4 stepping of one model with a fixed number of substeps."""

    def __init__(self, model: Model, substeps: int, compile: bool = True) -> None:
        self.model = model
        self.substeps = substeps
        nx = model.n_states
        nc = model.layout.input_size
        npar = model.layout.size
        stages = 2 * substeps + 1
        x = ca.MX.sym("x", nx)
        cin = ca.MX.sym("c", nc, stages)
        h = ca.MX.sym("h")
        p = ca.MX.sym("p", npar)
        dt = h / substeps
        xk = x
        for j in range(substeps):
            c0, c1, c2 = cin[:, 2 * j], cin[:, 2 * j + 1], cin[:, 2 * j + 2]
            k1 = model.rhs(xk, c0, p)
            k2 = model.rhs(xk + dt / 2 * k1, c1, p)
            k3 = model.rhs(xk + dt / 2 * k2, c1, p)
            k4 = model.rhs(xk + dt * k3, c2, p)
            xk = xk + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        step = ca.Function("step", [x, cin, h, p], [xk])
        reference = ca.MX.sym("x_ref", nx)
        self._step_parts = ([x, cin, h, p, reference], [xk, sensed_motion(model.kind, xk, reference)])
        self._single: Callable[..., list[np.ndarray]] | None = None
        self._compile = compile
        acc = step.mapaccum("acc", CHUNK)
        x0 = ca.MX.sym("x0", nx)
        cc = ca.MX.sym("C", cin.shape[0], stages * CHUNK)
        hh = ca.MX.sym("H", 1, CHUNK)
        pp = ca.MX.sym("p", npar)
        xs = acc(x0, cc, hh, ca.repmat(pp, 1, CHUNK))
        name = f"isolator_{model.tag}_s{substeps}"
        self.name = name
        self.chunk = NativeFunction(ca.Function(name, [x0, cc, hh, pp], [xs]), compile=compile)

    def step(
        self, x: np.ndarray, inputs: np.ndarray, h: float, p: np.ndarray, reference: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """One grid interval of length ``h`` [s] with stage inputs (2 substeps + 1, input size).

        Returns
        -------
        state : ndarray (n_states,)
            At the end of the interval.
        motion : ndarray (12,)
            What motion sensors see there (see :func:`sensed_motion`) relative to the state ``reference``.
        """
        if self._single is None:
            fn = ca.Function(f"{self.name}_one", *self._step_parts)
            self._single = NativeFunction(fn, compile=self._compile).bound()
        stages = inputs if inputs.shape[-1] else np.zeros((inputs.shape[0], 0))
        out, motion = self._single(x, stages, h, p, reference)
        return out.ravel().copy(), motion.ravel().copy()

    def run(self, x0: np.ndarray, inputs: np.ndarray, steps: np.ndarray, p: np.ndarray) -> np.ndarray:
        """States at the end of every interval.

        Parameters
        ----------
        x0 : ndarray (n_states,)
        inputs : ndarray (intervals, 2 substeps + 1, input size)
        steps : ndarray (intervals,)
            Interval lengths [s].
        p : ndarray
            Parameter vector.

        Returns
        -------
        ndarray (intervals, n_states)
        """
        n = steps.size
        nx = self.model.n_states
        out = np.empty((n, nx))
        x = np.asarray(x0, dtype=float)
        stage_shape = inputs.shape[1:]
        for start in range(0, n, CHUNK):
            stop = min(start + CHUNK, n)
            cin = inputs[start:stop]
            hs = steps[start:stop]
            if stop - start < CHUNK:
                pad = CHUNK - (stop - start)
                cin = np.concatenate([cin, np.repeat(cin[-1:], pad, axis=0)])
                hs = np.concatenate([hs, np.zeros(pad)])
            if stage_shape[-1] == 0:
                cin = np.zeros((CHUNK, 0))
            (xs,) = self.chunk(x, cin, hs, p)
            out[start:stop] = xs[: stop - start]
            x = xs[stop - start - 1]
        return out
