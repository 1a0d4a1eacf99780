"""Feedforward force histories optimised with casadi through the time-varying model.

The allocation (:func:`controllers.feedforward.feedforward_allocation`) asks
each actuator for the force that cancels the carriages' reaction *at that
instant*. Real actuators lag (``bandwidth``) and slew (``max_rate``), so the
force that arrives is late and rounded and the table rings. Here the command
is instead chosen over the whole move: piecewise linear between knots, it
drives the actuators' exact first-order lag, whose output acts on the table's
deviation ``e`` from its quasi-static path through the exact model linearised
**along the path** (carriages where and as fast as they are at each instant):

``M(t) e'' + C(t) e' + K(t) e = B(t) f(t) - w(t)``

with ``w`` the cancelling wrench and ``B`` the actuators' allocation (both from
:func:`controllers.feedforward.path.path_demand`). Pneumatic tables add the
chamber pressures' deviation ``p`` from the path's quasi-static pressures
(each group's air as at the start) to the state: ``+ Kp p`` on the left and
``p' = Pd e + Pv e' + Pp p + r(t)``, valves closed, with ``r`` what moving
along the path leaves (:class:`controllers.feedforward.path.AirDemand`;
:mod:`.optimal_stages`). The quadratic programme (solved
in multiple-shooting form, one RK4 step per knot interval; casadi gives each
interval's Jacobians, Clarabel solves the sparse QP) minimises the deviation,
normalised per signal by the passive run's, plus the vibration left at the end of the window, within ``max_force`` and
``max_rate``. Knots are 1 ms apart near the profiles' breakpoints (where the
demand changes fast) and coarser elsewhere.
The quasi-static tilt is left to leveling, as with the allocation.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy import sparse

from isolator.analysis.linear import linearise
from isolator.errors import OptimisationError, ScenarioError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.simulation.actuation import ForceHistory
from isolator.simulation.simulator import Simulator
from isolator.simulation.time_grid import grid_breakpoints

from .allocation import Feedforward
from .comparison import path_deviation
from .optimal_stages import interval_function, stage_data
from .path import path_demand, quasi_static_path

__all__ = ["OptimalSettings", "feedforward_optimal"]


@dataclass(frozen=True)
class OptimalSettings:
    """Knobs of the optimal feedforward.

    Attributes
    ----------
    fine, coarse : float
        Knot spacing [s] near breakpoints and elsewhere (multiples of the
        output sample period).
    before, after : float
        The fine stretch around each breakpoint [s].
    tail : float
        How long after the last carriage stops the actuators may still act [s].
    terminal_weight : float
        Weight of the vibration left at the end of the window (the table's
        deviation and its rate; not a pneumatic table's pressures, whose slow
        part is the groups' air, which the runs are measured about), against the
        time integral of the squared normalised deviation [s].
    effort_weight : float
        Weight of the squared forces over ``max_force`` (regularisation).
    max_iterations : int
        Interior-point iterations.
    tolerance : float
        The solver's gap and feasibility tolerance (scaled problem).
    """

    fine: float = 1e-3
    coarse: float = 1e-2
    before: float = 0.03
    after: float = 0.12
    tail: float = 0.3
    terminal_weight: float = 10.0
    effort_weight: float = 1e-4
    max_iterations: int = 100
    tolerance: float = 1e-10


def _knot_times(scenario: Scenario, settings: OptimalSettings) -> np.ndarray:
    """Knots [s] on the output sample grid (plus off-grid breakpoints); the last ends the window."""
    sim = scenario.simulation
    stop = scenario.stop_time
    if not math.isfinite(stop):
        raise ScenarioError("carriages: optimal feedforward needs moves that stop (a sine never does)")
    end = min(sim.duration, stop + settings.tail)
    period = 1.0 / sim.sample_rate
    fine = max(1, round(settings.fine / period))
    coarse = max(fine, round(settings.coarse / period))
    n_end = math.floor(end * sim.sample_rate + 1e-9)
    index = np.arange(n_end + 1)
    t = index * period
    bps = grid_breakpoints(sim, scenario.breakpoints)
    bps = bps[bps < end]
    near = np.zeros(t.size, bool)
    for b in bps:
        near |= (t >= b - settings.before) & (t <= b + settings.after)
    keep = (index % coarse == 0) | (near & (index % fine == 0))
    keep[0] = keep[-1] = True
    return np.union1d(t[keep], bps)


@dataclass(frozen=True)
class _QP:
    """``min 1/2 x' P x`` s.t. ``A x = b`` and ``lower <= C x <= upper``, in scaled variables ``x = D^-1 z``."""

    p: sparse.csc_matrix
    a: sparse.csc_matrix
    b: np.ndarray
    c: sparse.csc_matrix
    lower: np.ndarray
    upper: np.ndarray
    scale: np.ndarray  # D: z = D x


def _assemble(
    interval: ca.Function,
    n_lag: int,
    h: np.ndarray,
    data: np.ndarray,
    scale: np.ndarray,
    omega: float,
    cap: np.ndarray,
    lag_scale: np.ndarray,
    rates: list[float | None],
    settings: OptimalSettings,
    air_scale: np.ndarray | None = None,
) -> _QP:
    """The sparse QP in the knot-wise variables ``z_k = [e_k, f_k, u_k]``, k = 0 .. n.

    The dynamics are affine, so each interval's map is its Jacobian (casadi,
    evaluated for all intervals in one call) plus an offset. Variables and
    dynamics rows are scaled so that the passive run's deviation and the
    actuators' ``max_force`` are 1 (pneumatic tables: the chamber pressures'
    deviations by ``air_scale`` [Pa]).
    """
    n = h.size
    n_a = cap.size
    air_scale = np.zeros(0) if air_scale is None else air_scale
    n_dev = 12 + air_scale.size  # the deviation: d, d', then the chamber pressures
    nx = n_dev + n_lag
    m = nx + n_a
    decision = ca.SX.sym("z", nx + 2 * n_a)
    step = ca.SX.sym("h")
    table = ca.SX.sym("d", interval.size_in(5)[0])
    parts = ca.vertsplit(decision, [0, n_dev, nx, nx + n_a, nx + 2 * n_a])
    outs = ca.vertcat(*interval(*parts, step, table))
    jac = ca.Function("interval_jacobian", [decision, step, table], [ca.jacobian(outs, decision), outs])
    jacs, offsets = jac.map(n, "serial")(np.zeros((decision.shape[0], n)), h[None, :], data.T)
    # (n, nx, columns [e_k, f_k, u_k, u_k+1]); the map puts the intervals' Jacobians side by side
    jacs = np.asarray(jacs, dtype=float).reshape(nx, nx + 2 * n_a, n, order="F").transpose(2, 0, 1)
    offsets = np.asarray(offsets, dtype=float)  # (nx, n)
    # dynamics rows k: z_{k+1}[:nx] - J_k [z_k; u_k+1] = offset_k
    k, r, c = np.meshgrid(np.arange(n), np.arange(nx), np.arange(nx + 2 * n_a), indexing="ij")
    col = np.where(c < m, k * m + c, (k + 1) * m + nx + (c - m))
    vals = -jacs
    keep = vals != 0
    rows = np.concatenate([(k * nx + r)[keep], (np.arange(n)[:, None] * nx + np.arange(nx)).ravel()])
    cols = np.concatenate([col[keep], ((np.arange(n)[:, None] + 1) * m + np.arange(nx)).ravel()])
    values = np.concatenate([vals[keep], np.ones(n * nx)])
    dynamics = sparse.csc_matrix((values, (rows, cols)), shape=(n * nx, (n + 1) * m))
    # fixed values: rest at the start, zero command at the end
    fixed = np.concatenate([np.arange(nx), n * m + nx + np.arange(n_a)])
    pin = sparse.csc_matrix((np.ones(fixed.size), (np.arange(fixed.size), fixed)), shape=(fixed.size, (n + 1) * m))
    # scaling: z = D x, rows of the dynamics by the state scales
    state_scale = np.concatenate([1 / scale, 1 / (scale * omega), air_scale, lag_scale])
    d = np.tile(np.concatenate([state_scale, cap]), n + 1)
    row_scale = np.tile(1 / state_scale, n)
    a = sparse.vstack([sparse.diags(row_scale) @ dynamics, pin]) @ sparse.diags(d)
    b = np.concatenate([row_scale * offsets.T.ravel(), np.zeros(fixed.size)])
    # inequalities: force limits (|u| <= 1 scaled) and rate limits
    u_index = (np.arange(n + 1)[:, None] * m + nx + np.arange(n_a)).ravel()
    rows_c = [sparse.csc_matrix((np.ones(u_index.size), (np.arange(u_index.size), u_index)),
                                shape=(u_index.size, (n + 1) * m))]
    lower = [-np.ones(u_index.size)]
    upper = [np.ones(u_index.size)]
    for j, rate in enumerate(rates):
        if rate is None:
            continue
        kk = np.arange(n)
        diff = sparse.csc_matrix(
            (np.concatenate([np.ones(n), -np.ones(n)]),
             (np.concatenate([kk, kk]), np.concatenate([(kk + 1) * m + nx + j, kk * m + nx + j]))),
            shape=(n, (n + 1) * m))
        rows_c.append(diff)
        lower.append(-rate * h / cap[j])
        upper.append(rate * h / cap[j])
    # cost: tracking (trapezoid weights), vibration left at the window's end, effort
    weights = np.concatenate([[h[0] / 2], (h[:-1] + h[1:]) / 2, [h[-1] / 2]])
    diag = np.zeros((n + 1, m))
    diag[:, :6] = 2 * weights[:, None]
    diag[-1, :12] += 2 * settings.terminal_weight  # the table's motion; the air's slow part is its own rest
    diag[:, nx:] = 2 * settings.effort_weight * weights[:, None]
    return _QP(sparse.diags(diag.ravel()).tocsc(), a.tocsc(), b, sparse.vstack(rows_c).tocsc(),
               np.concatenate(lower), np.concatenate(upper), d)


def _solve(qp: _QP, settings: OptimalSettings) -> tuple[np.ndarray, str, int, bool]:
    """Clarabel (interior point) on the QP; the unscaled variables, status, iterations, success."""
    import clarabel

    a = sparse.vstack([qp.a, qp.c, -qp.c]).tocsc()
    b = np.concatenate([qp.b, qp.upper, -qp.lower])
    cones = [clarabel.ZeroConeT(qp.a.shape[0]), clarabel.NonnegativeConeT(2 * qp.c.shape[0])]
    options = clarabel.DefaultSettings()
    options.verbose = False
    options.max_iter = settings.max_iterations
    options.tol_gap_abs = options.tol_gap_rel = settings.tolerance
    options.tol_feas = settings.tolerance
    options.equilibrate_enable = False  # _assemble scales the problem; Clarabel's own scaling stalls it
    solver = clarabel.DefaultSolver(sparse.triu(qp.p).tocsc(), np.zeros(qp.p.shape[0]), a, b, cones, options)
    solution = solver.solve()
    status = str(solution.status)
    ok = status in ("Solved", "AlmostSolved")
    return qp.scale * np.asarray(solution.x), status, int(solution.iterations), ok


def feedforward_optimal(
    scenario: Scenario,
    settings: OptimalSettings | None = None,
    progress: bool = False,
) -> Feedforward:
    """Optimise the actuators' command through the time-varying model (see the module docstring).

    Parameters
    ----------
    scenario : Scenario
        With ``[[actuators]]`` and moves that stop.
    settings : OptimalSettings, optional
        Knot spacing, weights, the window after the stop and the solver's limits; default
        :class:`OptimalSettings`.
    progress : bool
        Print what is being solved and how it went.

    Returns
    -------
    Feedforward
        ``method="optimal"``; ``info`` holds the solver's status, iterations,
        knots, variables, time [s] and the window's end [s].

    Raises
    ------
    OptimisationError
        The QP solver (Clarabel) stopped without converging; the message gives
        its status (``exc.feedforward`` holds the best point's forces).
    """
    settings = settings or OptimalSettings()
    if not scenario.actuators:
        raise ScenarioError("actuators: the scenario has no [[actuators]] for feedforward")
    began = time.perf_counter()
    acts = scenario.actuators
    n_a = len(acts)
    knots = _knot_times(scenario, settings)
    h = np.diff(knots)
    n = h.size
    lin = linearise(scenario)
    path = quasi_static_path(scenario)
    data = stage_data(scenario, lin, path, knots)
    lagged = [k for k, a in enumerate(acts) if a.bandwidth is not None]
    tau = np.array([1.0 / (2 * math.pi * acts[k].bandwidth) for k in lagged])  # type: ignore[operator]
    n_air = 0 if lin.air is None else len(lin.air.names)
    interval = interval_function(n_a, tau, lagged, n_air)

    # normalise each signal by the passive run's deviation from the quasi-static path
    passive = Simulator(scenario).run()
    deviation = np.array(list(path_deviation(passive, path(passive.t).T).values()))
    # signals the move leaves (nearly) still weigh as if they moved 0.1 % of their group's largest
    floor = np.repeat([1e-3 * max(deviation[:3].max(), 1e-12), 1e-3 * max(deviation[3:].max(), 1e-12)], 3)
    scale = 1.0 / np.maximum(deviation, floor)
    omega = float(np.median(np.abs(lin.eigenvalues)))
    air_scale = None
    if n_air:  # the chamber pressures by the passive run's deviation from the path's [Pa]
        quasi_static = lin.equilibrium.state[13:] + path.pressures(passive.t)
        air_dev = np.max(np.abs(passive.states[:, 13:] - quasi_static), axis=0)
        air_scale = np.maximum(air_dev, 1e-3 * max(air_dev.max(), 1e-6))

    cap = np.array([a.max_force for a in acts])
    qp = _assemble(interval, len(lagged), h, data, scale, omega, cap, cap[lagged], [a.max_rate for a in acts],
                   settings, air_scale)
    if progress:
        print(f"  optimal feedforward: {n + 1} knots over {knots[-1]:.3g} s, {qp.p.shape[0]} variables ...",
              flush=True)
    z, status, iterations, ok = _solve(qp, settings)
    forces = z.reshape(n + 1, -1)[:, 12 + n_air + len(lagged):].T
    n_vars = int(qp.p.shape[0])
    elapsed = time.perf_counter() - began
    info = {"status": status, "iterations": iterations,
            "knots": int(n + 1), "variables": n_vars, "seconds": elapsed, "window_end": float(knots[-1])}
    if progress:
        print(f"  optimal feedforward: {info['status']} after {info['iterations']} iterations, {elapsed:.1f} s",
              flush=True)
    demand = path_demand(scenario, lin, path, knots, knots + 1e-12)
    residual = demand.wrench - np.einsum("nij,jn->ni", demand.allocation, forces)
    result = Feedforward(ForceHistory(knots, forces, tuple(a.name for a in acts)), demand.wrench, residual, path,
                         "optimal", info)
    if not ok:
        error = OptimisationError(
            f"optimal feedforward: the QP solver (Clarabel) stopped with '{info['status']}' after "
            f"{info['iterations']} iterations; "
            "the best point found is kept (raise OptimalSettings.max_iterations, or use --method allocation)"
        )
        error.feedforward = result  # type: ignore[attr-defined]
        raise error
    return result


check_public(globals())
