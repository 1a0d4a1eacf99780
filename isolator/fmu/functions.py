"""The plant FMU's model as casadi functions, generated as C: the right-hand side with the actuators' clipping
and lag, the outputs, the static residual and the rest state.

The functions are the toolkit's own exact model (:func:`isolator.model.cache.get_model`, built with the floor's
motion among the inputs so that a host can move the floor), its sensors' readings
(:func:`isolator.simulation.sampled_loop.readings`, as the compiled loop reads them) and the table's signals
(:meth:`~isolator.model.variants.ModelVariant.sensed_motion`); nothing of the equations is written again.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import casadi as ca
import numpy as np

from isolator.model.cache import get_model
from isolator.model.parameters import ParameterLayout
from isolator.model.variants import Model
from isolator.numerics.rk4 import BY_TIME, SPLIT, rk4_step
from isolator.scenario.definitions import Scenario
from isolator.simulation.actuation import lag_constants
from isolator.simulation.lag_steps import crosses, lag_rows, lag_weights
from isolator.simulation.sampled_loop import readings, rotation

__all__ = ["PlantFunctions", "plant_functions", "state_nominals"]


@dataclass(frozen=True)
class PlantFunctions:
    """The casadi functions the plant FMU's C is generated from.

    Attributes
    ----------
    model : Model
        The exact model with the floor's motion among its inputs.
    ode : casadi.Function
        ``(x, u, p) -> dx/dt`` of the FMU's state ``x`` (the model's state, then one force [N] per actuator
        with a lag) and the inputs ``u`` (the model's inputs with the actuators' commands in place of their
        forces).
    outputs : casadi.Function
        ``(x, u, p, ref, floor_acceleration) -> y``: the six table signals, the sensors, the points' x, y, z
        (and with ``positions``, each carriage's position along its axis [m], from ``u``).
    static : casadi.Function
        ``(z, c, p) -> (r, dr/dz)``: the static residual (:attr:`Model.static_residual`).
    pose : casadi.Function
        ``(z, p) -> x``: the FMU's state at rest in pose ``z`` (no lagged force).
    step : casadi.Function
        ``(x, u0, um, u1, h, p, W) -> x``: one RK4 step of ``h`` [s] of the FMU's state, the inputs at its start,
        middle and end (linear between), each lagged force taken exactly
        (:func:`~isolator.simulation.lag_steps.lag_stages`: the stages' forces, the lag's force at the end), the
        commands within their limits over the step (the lags' weights ``W`` of ``weights``).
    step_cut : casadi.Function
        The same step where a command crosses its limit inside it (the clipping's kinks followed).
    crossing : casadi.Function
        ``(u0, um, u1) -> 1`` where some lagged actuator's command crosses its limit inside the step.
    weights : casadi.Function
        ``h -> W``: the lags' weights for a step of ``h`` [s]
        (:func:`~isolator.simulation.lag_steps.lag_weights`).
    lagged : tuple of int
        The actuators with a lag, in order.
    """

    model: Model
    ode: ca.Function
    outputs: ca.Function
    static: ca.Function
    pose: ca.Function
    step: ca.Function
    step_cut: ca.Function
    crossing: ca.Function
    weights: ca.Function
    lagged: tuple[int, ...]

    @property
    def n_states(self) -> int:
        return self.model.n_states + len(self.lagged)


def plant_functions(scenario: Scenario, positions: bool = False) -> PlantFunctions:
    """The FMU's casadi functions of a scenario's structure (see :class:`PlantFunctions`); with ``positions``
    the outputs end with the carriages' positions (a plant whose carriages follow the profiles)."""
    layout = dataclasses.replace(ParameterLayout.of(scenario), ground=True)
    model = get_model(layout, "exact")
    nx, nu, npar = model.n_states, layout.input_size, layout.size
    acts = scenario.actuators
    lagged = tuple(k for k, a in enumerate(acts) if a.bandwidth is not None)
    x, u, p = ca.SX.sym("x", nx + len(lagged)), ca.SX.sym("u", nu), ca.SX.sym("p", npar)
    ref, floor_acc = ca.SX.sym("ref", nx + len(lagged)), ca.SX.sym("floor_acceleration", 3)
    commands = u[layout.actuator_slice]
    limits = ca.DM([a.max_force for a in acts])
    clipped = ca.fmin(ca.fmax(commands, -limits), limits) if acts else commands
    applied = [x[nx + lagged.index(k)] if k in lagged else clipped[k] for k in range(len(acts))]
    inputs = ca.vertcat(u[: layout.actuator_slice.start], *applied)
    rates = [(clipped[k] - x[nx + j]) * (2 * np.pi * float(acts[k].bandwidth or 0.0)) for j, k in enumerate(lagged)]
    xdot = ca.vertcat(model.rhs(x[:nx], inputs, p), *rates)
    ode = ca.Function("ode", [x, u, p], [xdot], ["x", "u", "p"], ["xdot"])

    ground = u[layout.ground_slice]
    floor = {0: ground[0:3], 1: ground[6:9], 2: floor_acc}
    table = readings(model, scenario.sensors, x[:nx], inputs, p, ref[:nx])
    sensors = [ca.dot(ca.DM(list(s.direction)), floor[s.order]) if s.on == "floor" else table[i]
               for i, s in enumerate(scenario.sensors)]
    rot, rot0 = rotation(x, "exact"), rotation(ref, "exact")
    flexible = layout.flexible
    points, elastic = [], []
    for pt in scenario.points:
        arm = ca.DM(list(pt.position))
        if flexible is None:
            points.append(x[0:3] + rot @ arm - ref[0:3] - rot0 @ arm)
            continue
        nm = flexible.n_modes  # a top that bends: the point's elastic translation, and its own outputs
        shape = ca.DM(flexible.shape_at(pt.position, pt.feet, f"points ({pt.name})"))
        now, then = shape @ x[13:13 + nm], shape @ ref[13:13 + nm]
        points.append(x[0:3] + rot @ (arm + now) - ref[0:3] - rot0 @ (arm + then))
        elastic.append(now - then)
    points += elastic
    carriages = [u[k] for k in range(layout.n_carriages)] if positions else []
    y = ca.vertcat(model.variant.sensed_motion(x[:nx], ref[:nx])[:6], *sensors, *points, *carriages)
    outputs = ca.Function("outputs", [x, u, p, ref, floor_acc], [y], ["x", "u", "p", "ref", "floor_acceleration"],
                          ["y"])
    z = ca.SX.sym("z", model.n_static)
    pose = ca.Function("pose", [z, p], [ca.vertcat(model.pose_state(z, p), ca.SX.zeros(len(lagged)))])
    return PlantFunctions(model, ode, outputs, model.static_residual, pose, *_steps(model, scenario, lagged), lagged)


def _steps(model: Model, scenario: Scenario, lagged: tuple[int, ...]
           ) -> tuple[ca.Function, ca.Function, ca.Function, ca.Function]:
    """The FMU's RK4 step (see :class:`PlantFunctions`): the simulator's steps of a forced run, one at a time, the
    lags' stage forces by :func:`~isolator.simulation.lag_steps.lag_rows`: the step within the limits, the step
    across them, which one a step is, and the lags' weights for a step's length (SX, so that the C evaluates
    only the step it takes, and the weights when the length changes)."""
    layout = model.layout
    nx, nu, na = model.n_states, layout.input_size, len(scenario.actuators)
    where, tau = layout.actuator_slice, lag_constants(scenario)
    limits = [a.max_force for a in scenario.actuators]
    lag_tau, lag_limits = [float(tau[k]) for k in lagged], [limits[k] for k in lagged]
    x, h, p = ca.SX.sym("x", nx + len(lagged)), ca.SX.sym("h"), ca.SX.sym("p", layout.size)
    us = [ca.SX.sym(name, nu) for name in ("u0", "um", "u1")]
    weights = ca.SX.sym("W", 6 * len(set(lag_tau)), 4)
    clipped = [ca.fmin(ca.fmax(u[where], -ca.DM(limits)), ca.DM(limits)) for u in us]
    picked = [ca.vertcat(*[u[where.start + k] for k in lagged]) for u in us]
    out = []
    for cut in (False, True):
        rows = ca.SX(0, 6) if not lagged else lag_rows(x[nx:], picked[0], picked[1], picked[2], h, lag_tau,
                                                        lag_limits, None if cut else weights)
        inputs = [ca.vertcat(us[t][: where.start], *[rows[lagged.index(k), i] if k in lagged else clipped[t][k]
                                                      for k in range(na)], us[t][where.stop:])
                  for i, t in enumerate(BY_TIME)]

        def rates(xs: ca.SX, stage: int, inputs: list[ca.SX] = inputs) -> ca.SX:
            return model.rhs(xs, inputs[stage], p)

        out.append(ca.Function("step_cut" if cut else "step", [x, *us, h, p, weights],
                               [ca.vertcat(rk4_step(rates, x[:nx], h, SPLIT), rows[:, 5])],
                               ["x", "u0", "um", "u1", "h", "p", "W"], ["x1"], {"cse": True}))
    crossing = ca.Function("crossing", us, [ca.sum1(crosses(picked[0], picked[1], picked[2], ca.DM(lag_limits))) > 0
                                            if lagged else ca.SX(0.0)])
    lag = ca.Function("lag_weights", [h], [lag_weights(h, sorted(set(lag_tau)))], {"cse": True})
    return out[0], out[1], crossing, lag


def state_nominals(functions: PlantFunctions, rest: np.ndarray) -> np.ndarray:
    """Each FMU state's nominal scale: the size of a change a host's solver should resolve, from which it
    sets its absolute tolerances (relative tolerance x nominal).

    Positions 1 um; the quaternion 1 urad (its vector part; its scalar part 1); velocities 1 um/s and
    angular velocities 1 urad/s; pressures 1e-6 of their rest value (a pressure that moves the table 1 um
    changes by more); lagged forces 1e-6 N.
    """
    nx = functions.model.n_states
    out = np.full(functions.n_states, 1e-6)
    out[3] = 1.0
    flexible = functions.model.layout.flexible
    if flexible is not None:  # modal coordinates and rates: those that move the top's attachments by 1 um
        largest = max((float(np.max(np.abs(flexible.shape_matrix(s)))) for s in flexible.isolators), default=1.0)
        out[13:nx] = 1e-6 / max(largest, 1e-12)
    elif nx > 13:
        out[13:nx] = np.maximum(1e-6 * np.abs(rest[13:nx]), 1e-3)
    return out
