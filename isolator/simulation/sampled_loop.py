"""The closed loop in compiled code: the plant stepped RK4 interval by interval, a sampled controller ticking.

One casadi function advances one grid interval: at a tick it reads the sensors at the interval's start
``t_k``, adds the tick's offsets (noise, minus the readings at the initial equilibrium, a reference path,
a floor sensor's signal), interpolates the controller's matrices with the tick's weights, updates the
controller and the held command; then it adds the feedforward command at every RK4 stage time, clips it at
``max_force``, lags it exactly (the first-order lag of :func:`~isolator.simulation.actuation.applied_forces`,
the command linear between stage times, its kinks at the limits followed) and steps the plant, each RK4 stage
taking a lagged force as :func:`~isolator.simulation.actuation.lag_stages` gives it (so that the steps follow
the table's own rates, not the lags'). ``CHUNK`` such intervals are one compiled
call (:class:`~isolator.numerics.native.NativeFunction`, cached on disk); the controller's matrices, the
actuators' limits and lags and the delay flag are arguments, so another controller of the same shape runs
without compiling. Functions are built once per model, substeps, controller shape and sensor set.

Readings at ``t_k`` are the sensors' signals of :mod:`isolator.simulation.sensors` (table sensors; a floor
sensor's signal is a known function of time and comes in the offsets) of the state at ``t_k``. An
acceleration sensor reads the left limit there: the right-hand side with the inputs (carriages and applied
forces) just before ``t_k`` (at ``t_0``, with the inputs at ``t_0`` and zero force).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from isolator.errors import SimulationError
from isolator.model.rotations import cardan_matrix, quaternion_to_matrix
from isolator.model.variants import Model
from isolator.numerics.native import NativeFunction
from isolator.numerics.rk4 import BY_TIME, SPLIT, rk4_step
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.sensors import Sensor
from isolator.simulation.controller_schema import spectral_radius
from isolator.simulation.lag_steps import crosses, lag_stages
from isolator.simulation.sensors import _motion_function, modal_count

__all__ = ["CHUNK", "LoopRun", "SampledLaw", "SampledLoop", "readings", "rotation", "sampled_loop"]

#: grid intervals per compiled call
CHUNK = 256
#: the most entries of a controller's ``A`` and ``B`` whose tick is written out as scalar operations (more: as
#: dense matrix products, whose code does not grow with the controller)
_SCALAR_TICK = 8192

Matrices = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


@dataclass(frozen=True, eq=False)
class SampledLaw:
    """A sampled linear controller as the compiled loop runs it.

    At each tick ``t_k`` with readings ``y_k`` (the inputs plus the tick's offsets) and the tick's weights
    ``w_k``: ``(A, B, C, D) = sum_j w_kj (A_j, B_j, C_j, D_j)``, ``u_k = C x_k + D y_k`` [N],
    ``x_{k+1} = A x_k + B y_k``; ``u_k`` is held from ``t_k`` (from ``t_{k+1}`` with ``delay``).

    Attributes
    ----------
    sample_rate : float
        [Hz].
    matrices : tuple of (A, B, C, D)
        The design points (one for a fixed controller), all of the same shapes.
    sensors : tuple of Sensor, optional
        The inputs: these sensors' readings (SI units); None: the table's 12 sensed motion states
        (displacement [m] and rotation vector [rad] from the initial equilibrium, velocity [m/s], angular
        velocity [rad/s], world axes).
    offsets : callable, optional
        ``t (ticks,) [s] -> (ticks, inputs)`` added to the readings at the ticks (default none).
    weights : callable, optional
        ``t (ticks,) [s] -> (ticks, design points)`` (default: the first point alone).
    delay : bool
        One sample of computation delay.
    name : str
        How errors name it (a controller that diverges is one).
    """

    sample_rate: float
    matrices: Sequence[Matrices]
    sensors: tuple[Sensor, ...] | None = None
    offsets: Callable[[np.ndarray], np.ndarray] | None = None
    weights: Callable[[np.ndarray], np.ndarray] | None = None
    delay: bool = False
    name: str = "controller"

    @property
    def shape(self) -> tuple[int, int, int, int]:
        """(states, inputs, outputs, design points)."""
        a, b, c, _ = self.matrices[0]
        return a.shape[0], b.shape[1], c.shape[0], len(self.matrices)

    def packed(self) -> np.ndarray:
        """Every design point's matrices, column-major, one after the other (the compiled function's input)."""
        return np.concatenate([np.concatenate([m.ravel(order="F") for m in point]) for point in self.matrices])


def rotation(x: ca.SX, kind: str) -> ca.SX:
    """The table's rotation matrix of a state, as the model's own equations build it: Cardan angles in
    ``x[3:6]`` ("paper") or the quaternion in ``x[3:7]`` (normalised)."""
    return cardan_matrix(x[3:6]) if kind == "paper" else quaternion_to_matrix(x[3:7])


def readings(model: Model, sensors: tuple[Sensor, ...] | None, x: ca.SX, c: ca.SX, p: ca.SX, ref: ca.SX) -> ca.SX:
    """The inputs' noise-free readings at a state (floor sensors: zero, their signal is an offset)."""
    if sensors is None:
        return model.variant.sensed_motion(x, ref)
    sensed = _motion_function(model)(x, c, p, ref)
    motion, rates = sensed[0], sensed[1]
    rot, rot0 = rotation(x, model.kind), rotation(ref, model.kind)
    flexible = model.layout.flexible
    nm = modal_count(model)
    modal = None if flexible is None else (x[13:13 + nm], x[13 + nm:13 + 2 * nm], sensed[2], ref[13:13 + nm])
    out = []
    for s in sensors:
        if s.on != "table":
            out.append(ca.SX(0.0))
            continue
        arm, n = ca.DM(list(s.position)), ca.DM(list(s.direction))
        lever, lever0 = ca.SX(arm), ca.SX(arm)
        moving, accelerating = ca.SX.zeros(3, 1), ca.SX.zeros(3, 1)
        if flexible is not None and modal is not None:  # a top that bends: the elastic translation there
            shape = ca.DM(flexible.shape_at(s.position, None, f"sensors ({s.name})"))
            lever, lever0 = arm + shape @ modal[0], arm + shape @ modal[3]
            moving, accelerating = rot @ (shape @ modal[1]), rot @ (shape @ modal[2])
        turned = rot @ lever
        w = motion[9:12]
        if s.order == 0:
            value = x[0:3] + turned - ref[0:3] - rot0 @ lever0
        elif s.order == 1:
            value = motion[6:9] + ca.cross(w, turned) + moving
        else:
            value = (rates[0:3] + ca.cross(rates[3:6], turned) + ca.cross(w, ca.cross(w, turned))
                     + 2 * ca.cross(w, moving) + accelerating)
        out.append(ca.dot(n, value))
    return ca.vertcat(*out)


def _tick(shape: tuple[int, int, int, int]) -> ca.Function:
    """``(xc, hold, pending, y, tick, w, M, delay) -> (xc, hold, pending)``: the controller at a tick (SX; MX for a
    large controller, whose scalar code would grow with its ``n^2`` entries)."""
    n, ny, m, k = shape
    sym: Any = ca.MX.sym if n * (n + ny) > _SCALAR_TICK else ca.SX.sym  # large: dense loops, code of fixed size
    xc, hold, pending, y, tick, weights, delay = sym("xc", n), sym("hold", m), sym("pending", m), sym("y", ny), \
        sym("tick"), sym("w", k), sym("delay")
    sizes = [(n, n), (n, ny), (m, n), (m, ny)]
    per = sum(r * c for r, c in sizes)
    packed = sym("M", k * per)
    mixed = packed if k == 1 else sum((weights[j] * packed[j * per:(j + 1) * per] for j in range(k)),
                                      ca.DM.zeros(per, 1))
    mats, at = [], 0
    for r, c in sizes:
        mats.append(ca.reshape(mixed[at:at + r * c], r, c))
        at += r * c
    a, b, cm, d = mats
    command = cm @ xc + d @ y
    outs = [ca.if_else(tick, a @ xc + b @ y, xc), ca.if_else(tick, ca.if_else(delay, pending, command), hold),
            ca.if_else(tick, command, pending)]
    return ca.Function("tick", [xc, hold, pending, y, tick, weights, packed, delay], outs)


def _actuators(m: int, substeps: int) -> ca.Function:
    """``(hold, ff, h, lag, limits, tau, lagged) -> (applied (m, stages), taken (m, 4 substeps), lag)``: the command
    plus feedforward at the stage times, clipped; what acts at the stage times, and what each RK4 stage takes (a
    lag's force through :func:`~isolator.simulation.lag_steps.lag_stages`). The clipping's kinks inside a step
    are followed only in an interval where a command crosses its limit (a conditional call; elsewhere the two
    halves of the clipped command give the same numbers at a fraction of the cost). One substep's lag is a small
    function called once per substep: written out for every substep, a bending top's 39 substeps of twelve
    actuators were 20 MB of C that the compiler could not hold in 24 GB."""
    sym = ca.SX.sym
    stages = 2 * substeps + 1
    r, u = [sym(f"r{k}", m) for k in range(3)], [sym(f"u{k}", m) for k in range(3)]
    hs, lag, limits, tau, lagged = sym("h"), sym("lag", m), sym("limits", m), sym("tau", m), sym("lagged", m)
    steps = []
    for cut in (False, True):  # one substep: what its four stages take, the forces at its middle and end, the lag
        ramps = r if cut else u
        stage, (half, end) = lag_stages(lag, ramps[0], ramps[1], ramps[2], hs, tau, limits if cut else None)
        taken = [ca.if_else(lagged, b, u[k]) for b, k in zip(stage, BY_TIME, strict=True)]
        steps.append(ca.Function("lag_cut" if cut else "lag", [*r, *u, hs, lag, limits, tau, lagged],
                                 [ca.horzcat(*taken), ca.if_else(lagged, half, u[1]), ca.if_else(lagged, end, u[2]),
                                  end]))
    one_kink = ca.Function("kinks", [*r, limits], [ca.sum1(crosses(r[0], r[1], r[2], limits))])
    mx = ca.MX.sym
    hold, ff, h, lag0 = mx("hold", m), mx("ff", m, stages), mx("h"), mx("lag", m)
    limits_m, tau_m, lagged_m = mx("limits", m), mx("tau", m), mx("lagged", m)
    args = [hold, ff, h, lag0, limits_m, tau_m, lagged_m]
    raw = [hold + ff[:, j] for j in range(stages)]
    clipped = [ca.fmin(ca.fmax(v, -limits_m), limits_m) for v in raw]
    branches = []
    for cut, step in zip((False, True), steps, strict=True):
        lags, acting, stage_forces = lag0, [ca.if_else(lagged_m, lag0, clipped[0])], []
        for j in range(substeps):
            nodes = slice(2 * j, 2 * j + 3)
            four, half, end, lags = step(*raw[nodes], *clipped[nodes], h / substeps, lags, limits_m, tau_m, lagged_m)
            stage_forces.append(four)
            acting += [half, end]
        branches.append(ca.Function("actuators_cut" if cut else "actuators", args,
                                    [ca.horzcat(*acting), ca.horzcat(*stage_forces), lags]))
    which = ca.Function("crossing", args, [sum(one_kink(*raw[2 * j:2 * j + 3], limits_m) for j in range(substeps))])
    switch = ca.Function.conditional("actuators_switch", [branches[0]], branches[1])
    return ca.Function("actuators", args, [*switch(which(*args) > 0, *args)])


def _interval(model: Model, substeps: int, actuators: slice, shape: tuple[int, int, int, int],
              sensors: tuple[Sensor, ...] | None) -> ca.Function:
    """One grid interval of the closed loop (see the module's description): MX calling small SX functions,
    so that the compiled code stays small (the right-hand side's code is shared by every RK4 stage)."""
    n, ny, m, k = shape
    nx, nc, npar = model.n_states, model.layout.input_size, model.layout.size
    stages = 2 * substeps + 1
    xs, cs, ps, rs = ca.SX.sym("x", nx), ca.SX.sym("c", nc), ca.SX.sym("p", npar), ca.SX.sym("ref", nx)
    reading = ca.Function("readings", [xs, cs, ps, rs], [readings(model, sensors, xs, cs, ps, rs)])
    sym = ca.MX.sym
    x, xc, hold, pending, lag, cprev = sym("x", nx), sym("xc", n), sym("hold", m), sym("pending", m), \
        sym("lag", m), sym("cprev", nc)
    cin, h, p, ref = sym("c", nc, stages), sym("h"), sym("p", npar), sym("ref", nx)
    tick, offset, weights, ff = sym("tick"), sym("offset", ny), sym("w", k), sym("ff", m, stages)
    packed = sym("M", k * (n * n + n * ny + m * n + m * ny))
    delay, limits, tau, lagged = sym("delay"), sym("limits", m), sym("tau", m), sym("lagged", m)
    y = reading(x, cprev, p, ref) + offset
    xc_next, hold_next, pending_next = _tick(shape)(xc, hold, pending, y, tick, weights, packed, delay)
    applied, taken, lags = _actuators(m, substeps)(hold_next, ff, h, lag, limits, tau, lagged)
    inputs = [ca.vertcat(cin[: actuators.start, j], applied[:, j], cin[actuators.stop:, j]) for j in range(stages)]
    dt = h / substeps
    xk = x
    for s in range(substeps):
        at4 = tuple(ca.vertcat(cin[: actuators.start, 2 * s + k], taken[:, 4 * s + i], cin[actuators.stop:, 2 * s + k])
                    for i, k in enumerate(BY_TIME))

        def rates(xs: ca.MX, stage: int, at4: tuple[ca.MX, ...] = at4) -> ca.MX:
            return model.rhs(xs, at4[stage], p)

        xk = rk4_step(rates, xk, dt, SPLIT)
    ins = [x, xc, hold, pending, lag, cprev, cin, h, p, ref, tick, offset, weights, ff, packed, delay, limits, tau,
           lagged]
    outs = [xk, xc_next, hold_next, pending_next, lags, inputs[-1], applied]
    return ca.Function("interval", ins, outs)


@dataclass(frozen=True)
class LoopRun:
    """What the compiled loop returns.

    Attributes
    ----------
    states : ndarray (intervals, n_states)
        After each interval (NaN from the first non-finite one on).
    applied : ndarray (intervals, stages, actuators)
        The forces acting at every RK4 stage time [N].
    """

    states: np.ndarray
    applied: np.ndarray


class SampledLoop:
    """The compiled closed loop of one model, substeps, controller shape and sensor set.

    Parameters
    ----------
    model : Model
    substeps : int
        RK4 steps per grid interval.
    shape : tuple of int
        (controller states, inputs, actuators, design points).
    sensors : tuple of Sensor, optional
        The controller's inputs (None: the 12 sensed motion states).
    compile : bool
        Compile (else casadi evaluates it).
    """

    def __init__(self, model: Model, substeps: int, shape: tuple[int, int, int, int],
                 sensors: tuple[Sensor, ...] | None, compile: bool = True) -> None:
        self.model, self.substeps, self.shape = model, substeps, shape
        step = _interval(model, substeps, model.layout.actuator_slice, shape, sensors)
        carried = [ca.MX.sym(step.name_in(i), *step.size_in(i)) for i in range(6)]
        stages, m = 2 * substeps + 1, shape[2]
        cin = ca.MX.sym("C", model.layout.input_size, stages * CHUNK)
        h, tick = ca.MX.sym("H", 1, CHUNK), ca.MX.sym("T", 1, CHUNK)
        offset, weights = ca.MX.sym("E", shape[1], CHUNK), ca.MX.sym("W", shape[3], CHUNK)
        ff = ca.MX.sym("F", m * stages, CHUNK)
        shared = [ca.MX.sym(step.name_in(i), *step.size_in(i)) for i in (8, 9)]
        consts = [ca.MX.sym(step.name_in(i), *step.size_in(i)) for i in range(14, 19)]
        state, xs, forces = list(carried), [], []
        for j in range(CHUNK):
            out = step.call([*state, cin[:, j * stages:(j + 1) * stages], h[j], *shared, tick[j], offset[:, j],
                             weights[:, j], ca.reshape(ff[:, j], m, stages), *consts])
            state = list(out[:6])
            xs.append(out[0])
            forces.append(ca.vec(out[6]))
        fn = ca.Function(f"isolator_loop_{model.tag}_s{substeps}_{'_'.join(map(str, shape))}_{len(sensors or ())}",
                         [*carried, cin, h, *shared, tick, offset, weights, ff, *consts],
                         [ca.horzcat(*xs), ca.horzcat(*forces), *state[1:]])
        self.chunk = NativeFunction(fn, compile=compile)

    def run(self, scenario: Scenario, law: SampledLaw, x0: np.ndarray, inputs: np.ndarray, steps: np.ndarray,
            p: np.ndarray, ticks: np.ndarray, offsets: np.ndarray, weights: np.ndarray,
            feedforward: np.ndarray | None) -> LoopRun:
        """Run over a grid.

        Parameters
        ----------
        scenario : Scenario
            For the actuators' limits [N] and lags.
        law : SampledLaw
        x0 : ndarray (n_states,)
            The initial equilibrium's state (also the reference of the readings).
        inputs : ndarray (intervals, stages, input size)
            The model's inputs at the stage times (actuator forces ignored).
        steps : ndarray (intervals,)
            Interval lengths [s].
        p : ndarray
            Parameter vector.
        ticks : ndarray of bool (intervals,)
            Intervals that start at a tick.
        offsets, weights : ndarray (intervals, inputs), (intervals, design points)
            Per interval (read at ticks only).
        feedforward : ndarray (intervals, stages, actuators), optional
            Commanded forces [N] added to the controller's before clipping and lag.
        """
        n, _, m, _ = self.shape
        stages = 2 * self.substeps + 1
        total = steps.size
        acts = scenario.actuators
        limits = np.array([a.max_force for a in acts], dtype=float)
        tau = np.array([1.0 / (2 * np.pi * a.bandwidth) if a.bandwidth is not None else 1.0 for a in acts])
        lagged = np.array([a.bandwidth is not None for a in acts], dtype=float)
        consts = (law.packed(), np.array([float(law.delay)]), limits, tau, lagged)
        c0 = inputs[0, 0].copy()
        c0[self.model.layout.actuator_slice] = 0.0
        carry = [np.asarray(x0, dtype=float), np.zeros(n), np.zeros(m), np.zeros(m), np.zeros(m), c0]
        none = np.zeros((CHUNK, stages, m))
        flags = ticks.astype(float)
        states, applied = np.empty((total, x0.size)), np.empty((total, stages, m))
        call = self.chunk.bound()  # buffers allocated once for the run's calls

        def advance(lo: int, hi: int, carry: list[np.ndarray]) -> list[np.ndarray]:
            """Intervals lo..hi (at most CHUNK) from ``carry``; the carry after them."""
            part = [inputs[lo:hi], steps[lo:hi], flags[lo:hi], offsets[lo:hi], weights[lo:hi],
                    none[: hi - lo] if feedforward is None else feedforward[lo:hi]]
            if hi - lo < CHUNK:  # padded with empty intervals, dropped
                part = [np.concatenate([a, np.zeros((CHUNK - (hi - lo), *a.shape[1:]))]) for a in part]
            cin, h, tick, offset, weight, force = part
            xs, forces, *rest = call(*carry, cin, h, p, x0, tick, offset, weight, force, *consts)
            states[lo:hi] = xs[: hi - lo]
            applied[lo:hi] = forces[: hi - lo].reshape(hi - lo, stages, m)
            return [xs[hi - lo - 1].copy(), *(r.ravel().copy() for r in rest)]

        for lo in range(0, total, CHUNK):
            hi = min(lo + CHUNK, total)
            before, carry = carry, advance(lo, hi, carry)
            if not all(np.all(np.isfinite(c)) for c in carry[1:3]):  # the controller's state, its command
                for j in range(lo, hi):  # which interval (only once the run has failed: one call each)
                    before = advance(j, j + 1, before)
                    if not all(np.all(np.isfinite(c)) for c in before[1:3]):
                        raise _diverged(law, int(np.sum(ticks[: j + 1])) - 1)
        bad = ~np.all(np.isfinite(states), axis=1)
        if bad.any():
            states[int(np.argmax(bad)):] = np.nan
        return LoopRun(states, applied)


def _diverged(law: SampledLaw, sample: int) -> SimulationError:
    """The error of a controller whose state or command stopped being finite at ``sample``."""
    radius = spectral_radius([a for a, *_ in law.matrices])
    return SimulationError(f"{law.name}: a non-finite state or command at sample {sample} (t = "
                           f"{sample / law.sample_rate:.6g} s): the controller diverged (the spectral radius of its "
                           f"A is {radius:.6g}{'; > 1: unstable on its own' if radius > 1 else ''}): the run is "
                           "refused rather than its NaN commands clipped to the force limits")


_LOOPS: dict[tuple[object, ...], SampledLoop] = {}


def sampled_loop(model: Model, substeps: int, law: SampledLaw) -> SampledLoop:
    """The compiled loop for a model, substeps and the law's shape and sensors (built once)."""
    sensors = law.sensors
    key = (model.layout, model.kind, substeps, law.shape,
           None if sensors is None else tuple((s.on, s.position, s.direction, s.order) for s in sensors))
    if key not in _LOOPS:
        _LOOPS[key] = SampledLoop(model, substeps, law.shape, sensors)
    return _LOOPS[key]


check_public(globals())
