"""The scenario's ``[[sensors]]`` read from a run's states: the columns ``s:<sensor>`` of simulation results.

A table sensor at the point ``r`` (table frame, from the mass centre) along the world direction ``n``
measures (``docs/scenario-format.md``, "Calibration from measured records"):

- displacement ``n . (P(t) - P(0))`` [m], with ``P = c + R r`` the point's world position and ``P(0)`` its
  position at the initial equilibrium;
- velocity ``n . (v + w x R r)`` [m/s];
- acceleration ``n . (a + alpha x R r + w x (w x R r))`` [m/s^2], no gravity or tilt term;

with ``c, v, a`` the mass centre's position, velocity and acceleration and ``w, alpha`` the table's angular
velocity and acceleration (world axes). The accelerations are the model's own right-hand side at each sample
(the derivative of the sensed velocities along it, from the one casadi model). A floor sensor measures the
floor's translation along ``n`` (its displacement, velocity or acceleration from the ``[ground]`` profiles;
a still floor reads zero). Signals are noise-free.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

import casadi as ca
import numpy as np

from isolator.model.variants import Model
from isolator.numerics.native import MappedFunction
from isolator.scenario.definitions import Scenario
from isolator.scenario.sensors import Sensor
from isolator.simulation.points import point_positions, rotation_matrices

__all__ = ["floor_motion", "sensor_columns", "sensor_history", "sensor_signals", "table_motion"]


@lru_cache(maxsize=16)
def _motion_function(model: Model) -> ca.Function:
    """``(x, c, p, ref) -> (motion (12,), rates (6,))``: the sensed motion of the mass centre (displacement,
    rotation vector, velocity, angular velocity; world axes) and the time derivative of its velocities along
    the model's right-hand side; on a top that bends a third output, the modal accelerations (modes,) of that
    same right-hand side."""
    x = ca.SX.sym("x", model.n_states)
    ref = ca.SX.sym("ref", model.n_states)
    c = ca.SX.sym("c", model.layout.input_size)
    p = ca.SX.sym("p", model.layout.size)
    motion = model.variant.sensed_motion(x, ref)
    xdot = model.rhs(x, c, p)
    rates = ca.jacobian(motion[6:12], x) @ xdot
    nm = modal_count(model)
    return ca.Function("sensed_rates", [x, c, p, ref], [motion, rates] + ([xdot[13 + nm:13 + 2 * nm]] if nm else []))


def modal_count(model: Model) -> int:
    """The number of a bending top's modal coordinates in the model's state (0 on a rigid top)."""
    return 0 if model.layout.flexible is None else model.layout.flexible.n_modes


@lru_cache(maxsize=16)
def _mapped(model: Model) -> MappedFunction:
    """:func:`_motion_function` compiled for many states at once (the native build, cached on disk)."""
    return MappedFunction(_motion_function(model), f"isolator_sensed_{model.tag}", block=256, optimisation="-O1")


def table_motion(model: Model, states: np.ndarray, inputs: np.ndarray, p: np.ndarray, start: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The mass centre's velocity and acceleration, the table's angular velocity and angular acceleration
    (each (N, 3), world axes, [m/s], [m/s^2], [rad/s], [rad/s^2]) at states (N, n_states) with the model's
    inputs (N, input size) there and the parameter vector ``p``."""
    out = _mapped(model)(np.asarray(states, dtype=float), np.asarray(inputs, dtype=float),
                         np.asarray(p, dtype=float), np.asarray(start, dtype=float))
    motion, rates = out[0], out[1]
    return motion[:, 6:9], rates[:, 0:3], motion[:, 9:12], rates[:, 3:6]


def model_rates(model: Model, states: np.ndarray, inputs: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The model's right-hand side (N, n_states) at states (N, n_states) with its inputs (N, input size), as
    casadi evaluates the one symbolic model (as the compiled loop's readings do: equal to round-off of it)."""
    return np.asarray(model.rhs(states.T, inputs.T, p)).T


def floor_motion(scenario: Scenario, t: np.ndarray) -> np.ndarray:
    """The floor's translation, its velocity and its acceleration (3, 3, N) at times ``t`` [s]: [quantity order,
    axis x y z, sample] in [m], [m/s], [m/s^2] (zero for a still floor)."""
    t = np.asarray(t, dtype=float)
    out = np.zeros((3, 3, t.size))
    if scenario.ground is not None:
        for k, axis in enumerate("xyz"):
            if axis in scenario.ground.motion:
                out[:, k, :] = np.array(scenario.ground.motion[axis].evaluate(t, t))
    return out


def sensor_signals(scenario: Scenario, model: Model, t: np.ndarray, states: np.ndarray, inputs: np.ndarray,
                   p: np.ndarray, start: np.ndarray, sensors: tuple[Sensor, ...] | None = None) -> np.ndarray:
    """Every sensor's noise-free signal (sensors, N) in its SI quantity.

    Parameters
    ----------
    scenario : Scenario
    model : Model
        The model the states belong to.
    t : ndarray (N,)
        Sample times [s].
    states : ndarray (N, n_states)
    inputs : ndarray (N, input size)
        The model's inputs at the samples (carriages, floor, actuator forces).
    p : ndarray
        The run's parameter vector.
    start : ndarray (n_states,)
        The initial equilibrium's state (displacements are measured from it).
    sensors : tuple of Sensor, optional
        Default: the scenario's ``[[sensors]]``.
    """
    sensors = scenario.sensors if sensors is None else sensors
    states = np.atleast_2d(np.asarray(states, dtype=float))
    out = np.zeros((len(sensors), states.shape[0]))
    table = [i for i, s in enumerate(sensors) if s.on == "table"]
    if table:
        arms = np.array([sensors[i].position for i in table], dtype=float)
        directions = np.array([sensors[i].direction for i in table], dtype=float)
        orders = [sensors[i].order for i in table]
        by_order: dict[int, np.ndarray] = {}
        flexible = model.layout.flexible
        shapes = None if flexible is None else np.array(
            [flexible.shape_at(sensors[i].position, None, f"sensors ({sensors[i].name})") for i in table])
        if 0 in orders:
            moved = (point_positions(states, arms, model.kind, shapes)
                     - point_positions(start[None, :], arms, model.kind, shapes))
            by_order[0] = np.einsum("pin,pi->pn", moved, directions)
        if max(orders) > 0:
            v, a, w, alpha = table_motion(model, states, inputs, p, start)
            rot = rotation_matrices(states, model.kind)
            lever = np.broadcast_to(arms[:, None, :], (len(table), states.shape[0], 3))
            moving = accelerating = np.zeros_like(lever)
            if shapes is not None:  # a top that bends: the elastic translation at the sensor and its rates
                nm = shapes.shape[2]
                modal_acceleration = model_rates(model, states, inputs, p)[:, 13 + nm:13 + 2 * nm]
                lever = lever + np.einsum("pim,nm->pni", shapes, states[:, 13:13 + nm])
                moving = np.einsum("nij,pjm,nm->pni", rot, shapes, states[:, 13 + nm:13 + 2 * nm])
                accelerating = np.einsum("nij,pjm,nm->pni", rot, shapes, modal_acceleration)
            turned = np.einsum("nij,pnj->pni", rot, lever)  # (points, N, 3)
            by_order[1] = np.einsum("pni,pi->pn", v[None] + np.cross(w[None], turned) + moving, directions)
            by_order[2] = np.einsum("pni,pi->pn", a[None] + np.cross(alpha[None], turned)
                                    + np.cross(w[None], np.cross(w[None], turned)) + 2 * np.cross(w[None], moving)
                                    + accelerating, directions)
        for j, i in enumerate(table):
            out[i] = by_order[orders[j]][j]
    floor = [i for i, s in enumerate(sensors) if s.on == "floor"]
    if floor:
        ground = floor_motion(scenario, t)
        for i in floor:
            out[i] = np.asarray(sensors[i].direction, dtype=float) @ ground[sensors[i].order]
    return out


def sensor_history(scenario: Scenario, model: Model, t: np.ndarray, states: Callable[[], np.ndarray],
                   inputs: np.ndarray, p: np.ndarray, start: np.ndarray) -> Callable[[], np.ndarray] | None:
    """A run's sensor signals computed on first use (:func:`sensor_signals` of ``states()``); None without
    sensors."""
    if not scenario.sensors:
        return None
    return lambda: sensor_signals(scenario, model, t, states(), inputs, p, start)


def sensor_columns(sensors: tuple[Sensor, ...]) -> tuple[str, ...]:
    """The result columns ``s:<sensor>``."""
    return tuple(f"s:{s.name}" for s in sensors)
