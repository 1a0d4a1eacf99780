"""Runs with a sampled controller: what the compiled loop (:mod:`isolator.simulation.sampled_loop`) is given.

Two kinds of controller run there. A :class:`FeedbackLaw` (e.g. ``controllers.feedback.DiscreteLaw``) is
state feedback on the table's 12 sensed motion states minus its reference path; its sample rate must
divide the rate the simulation steps at. A
:class:`~isolator.simulation.discrete_controller.DiscreteController` (``controller.json``) reads the
scenario's sensors as ``docs/scenario-format.md`` says ("Sensors in the scenario, output feedback and
exported controllers"): each reading minus its reading at the initial equilibrium (the table at rest
there, the inputs at ``t = 0``), with each sensor's seeded noise when asked (white of its ``noise`` RMS per
sample, or of its ``noise_psd``: :mod:`isolator.simulation.sensor_noise`), and the carriages' raw
positions ``q(t_k)`` for a schedule. Its run steps at the least whole multiple of the output rate that is
1 kHz or more and a whole multiple of the controller's rate (:func:`controller_factor`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Protocol

import numpy as np

from isolator.analysis.sampling import MAX_SAMPLE_RATE
from isolator.errors import ParameterError
from isolator.model.equilibrium import Equilibrium
from isolator.model.variants import Model
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario, SimulationSettings
from isolator.scenario.names import escaped
from isolator.simulation.actuation import ForceHistory
from isolator.simulation.discrete_controller import DiscreteController
from isolator.simulation.sampled_loop import SampledLaw, sampled_loop
from isolator.simulation.sensor_noise import sensor_noise
from isolator.simulation.sensors import floor_motion, sensor_signals
from isolator.simulation.time_grid import (
    INTERNAL_RATE,
    TimeGrid,
    inputs_at,
    internal_rate,
    model_inputs,
    stage_times,
    time_grid,
)

__all__ = ["MAX_STEPPING_RATE", "FeedbackLaw", "LoopGrids", "closed_loop_run", "controller_factor", "controller_law",
           "controller_period", "run_closed_loop", "state_feedback"]

#: a simulator's closed-loop grids and their inputs, by (output rate's factor, substeps)
LoopGrids = dict[tuple[int, int], tuple[TimeGrid, np.ndarray]]
#: the fastest grid [Hz] a controller's run steps on (a grid for its rate is searched up to it)
MAX_STEPPING_RATE = MAX_SAMPLE_RATE


class FeedbackLaw(Protocol):
    """A sampled state-feedback law the simulation runs (e.g. :class:`controllers.feedback.DiscreteLaw`).

    At each tick ``t_k`` it reads the table's 12 sensed motion states (displacement [m] and rotation
    vector [rad] from the initial equilibrium, velocity [m/s], angular velocity [rad/s], world axes) minus
    ``references(t_k)``; ``matrices()`` map them to the commands [N], held until the next tick.

    Attributes
    ----------
    sample_rate : float
        [Hz]; must divide the rate the simulation steps at (its output sample rate, raised by a whole
        factor to 1 kHz or more: :func:`isolator.simulation.time_grid.internal_rate`).
    """

    sample_rate: float

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The discrete ``(A, B, C, D)`` from the 12 measured deviations to the commands [N]."""

    def references(self, t: np.ndarray) -> np.ndarray:
        """What the law regulates to at times ``t`` [s]: (len(t), 12), the measured states' units."""

    def final(self, passive: np.ndarray) -> np.ndarray:
        """The six signals' closed-loop final value given the passive one (the settling reference)."""


def controller_period(scenario: Scenario, feedback: FeedbackLaw) -> int:
    """Nodes of the regular internal grid per tick of a :class:`FeedbackLaw`."""
    rate, factor = internal_rate(scenario.simulation)
    ratio = rate / float(feedback.sample_rate)
    period = round(ratio) if math.isfinite(ratio) else 0
    if not (math.isfinite(ratio) and period >= 1 and abs(ratio - period) <= 1e-9 * ratio):
        steps = "" if factor == 1 else f" x {factor}, the rate the simulation steps at ({rate:.6g} Hz)"
        raise ParameterError(
            f"feedback: the controller's sample rate {feedback.sample_rate:.6g} Hz must divide the "
            f"scenario's simulation.sample_rate ({scenario.simulation.sample_rate:.6g} Hz){steps}"
        )
    return period


def controller_factor(settings: SimulationSettings, rate: float) -> tuple[int, int]:
    """The output rate's factor for a controller ticking at ``rate`` [Hz], and the grid nodes per tick.

    The least whole ``f`` with ``f * sample_rate >= 1 kHz`` a whole multiple of ``rate`` (to 1e-9), ``f *
    sample_rate <=`` :data:`MAX_STEPPING_RATE`; a ParameterError naming both rates when there is none.
    """
    output = settings.sample_rate
    most = max(1, math.floor(MAX_STEPPING_RATE / output * (1 + 1e-12)))
    for factor in range(max(1, math.ceil(INTERNAL_RATE / output * (1 - 1e-12))), most + 1):
        ratio = output * factor / rate
        if abs(ratio - round(ratio)) <= 1e-9 * ratio and round(ratio) >= 1:
            return factor, round(ratio)
    raise ParameterError(f"controller: its sample rate {rate:.6g} Hz fits no stepping grid of simulation.sample_rate "
                         f"{output:.6g} Hz (a whole multiple of both, >= {INTERNAL_RATE:g} Hz, at most "
                         f"{MAX_STEPPING_RATE:g} Hz)")


def state_feedback(feedback: FeedbackLaw) -> SampledLaw:
    """A :class:`FeedbackLaw` as the compiled loop runs it."""
    a, b, c, d = (np.asarray(m, dtype=float) for m in feedback.matrices())
    return SampledLaw(float(feedback.sample_rate), ((a, b, c, d),),
                      offsets=lambda t: -np.asarray(feedback.references(t), dtype=float).reshape(t.size, -1),
                      name=f"feedback law ({type(feedback).__name__})")


def controller_law(scenario: Scenario, model: Model, p: np.ndarray, start: Equilibrium,
                   controller: DiscreteController, noise: bool = False, seed: int = 0) -> SampledLaw:
    """A :class:`DiscreteController` of the scenario's sensors, actuators and carriages as the loop runs it.

    Parameters
    ----------
    noise : bool
        Add each sensor's noise to its readings [SI]: white of its ``noise`` RMS per sample, or a sequence
        at the controller's rate whose one-sided PSD below half that rate is its ``noise_psd``
        (:func:`~isolator.simulation.sensor_noise.sensor_noise`, over the run's ticks).
    seed : int
        Seed of the noise (numpy's default generator), one standard-normal draw per tick and sensor.

    Raises
    ------
    ParameterError
        Names that differ from the scenario's (the first one named).
    """
    controller.check_names(scenario)
    sensors = scenario.sensors
    t0 = np.zeros(1)
    c0 = inputs_at(scenario, t0, t0)  # zero actuator force
    rest = sensor_signals(scenario, model, t0, start.state[None, :], c0, p, start.state)[:, 0]
    floor = [i for i, s in enumerate(sensors) if s.on == "floor"]

    def offsets(t: np.ndarray) -> np.ndarray:
        out = np.broadcast_to(-rest, (t.size, rest.size)).copy()
        if floor:
            ground = floor_motion(scenario, t)
            for i in floor:
                out[:, i] += np.asarray(sensors[i].direction, dtype=float) @ ground[sensors[i].order]
        if noise:
            out += sensor_noise(sensors, np.random.default_rng(seed).standard_normal(out.shape),
                                controller.sample_rate)
        return out

    def weights(t: np.ndarray) -> np.ndarray:
        q = np.array([c.profile.evaluate(t, t)[0] for c in scenario.carriages]).reshape(-1, t.size).T
        return controller.schedule_weights(q)

    points = controller.schedule or (controller,)
    matrices = tuple((e.A, e.B, e.C, e.D) for e in points)
    return SampledLaw(controller.sample_rate, matrices, sensors, offsets,  # type: ignore[arg-type]
                      weights if controller.schedule else None, controller.delay,
                      f"controller (method '{escaped(controller.method, 40)}')")


def run_closed_loop(scenario: Scenario, model: Model, grid: TimeGrid, grid_inputs: np.ndarray, p: np.ndarray,
                    start: Equilibrium, substeps: int, forces: ForceHistory | None, law: SampledLaw, period: int
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Step the grid in the compiled loop, the law ticking every ``period`` regular nodes.

    Parameters
    ----------
    grid_inputs : ndarray (intervals, stages, inputs)
        The model's inputs at every RK4 stage of the grid (not changed).
    forces : ForceHistory, optional
        The feedforward command, added to the controller's before saturation and lag.

    Returns
    -------
    states : ndarray (intervals, n_states)
        After each interval (NaN from the first non-finite one on).
    inputs : ndarray (intervals, stages, inputs)
        With the applied forces [N].
    """
    regular = grid.regular
    ticks = regular[:-1] & ((np.cumsum(regular[:-1]) - 1) % period == 0)
    at = grid.nodes[:-1][ticks]
    _, ny, _, k = law.shape
    offsets, weights = np.zeros((ticks.size, ny)), np.zeros((ticks.size, k))
    weights[:, 0] = 1.0
    if law.offsets is not None:
        offsets[ticks] = law.offsets(at)
    if law.weights is not None:
        weights[ticks] = law.weights(at)
    feedforward = None
    if forces is not None:
        times, mid = stage_times(grid, substeps)
        feedforward = forces.command(times.ravel(), mid.ravel()).reshape(*times.shape, -1)
    run = sampled_loop(model, substeps, law).run(scenario, law, start.state, grid_inputs, np.diff(grid.nodes), p,
                                                 ticks, offsets, weights, feedforward)
    inputs = grid_inputs.copy()
    inputs[:, :, model.layout.actuator_slice] = run.applied
    return run.states, inputs


def closed_loop_run(scenario: Scenario, model: Model,
                    simulator: tuple[TimeGrid, Callable[[int], np.ndarray], Callable[..., int], LoopGrids],
                    p: np.ndarray, equilibria: tuple[Equilibrium, Equilibrium | None], substeps: int,
                    forces: ForceHistory | None, feedback: FeedbackLaw | None, controller: DiscreteController | None,
                    noise: bool = False, seed: int = 0) -> tuple[TimeGrid, np.ndarray, np.ndarray]:
    """A simulator's run with a feedback law or a controller, on the loop's grid.

    Parameters
    ----------
    simulator : tuple
        The simulator's grid, its ``grid_inputs(substeps)``, its ``substeps_for(omega, grid)`` (the RK4
        substeps rule) and its cache of closed-loop grids (filled here, the last four kept).
    equilibria : tuple
        The initial and the final equilibrium (None when a carriage never stops).
    substeps : int
        RK4 steps per interval of the simulator's grid (the loop's own grid gets its own by the rule).
    forces : ForceHistory, optional
        The feedforward command [N], added to the controller's before saturation and lag.
    feedback, controller
        The state-feedback law, or the controller of the scenario's sensors (one of them).
    noise, seed
        As for :func:`controller_law` (a controller only).

    Returns
    -------
    grid : TimeGrid
    states : ndarray (intervals, n_states)
        After each interval (NaN from the first non-finite one on).
    inputs : ndarray (intervals, stages, inputs)
        With the applied forces [N].
    """
    own, grid_inputs, substeps_for, cache = simulator
    start, end = equilibria
    internal = internal_rate(scenario.simulation)[1]
    if controller is not None and feedback is not None:
        raise ParameterError("controller: give either a controller or a feedback law, not both")
    if controller is None and noise:
        raise ParameterError("noise: adds sensor noise to a controller's readings; give a controller")
    if controller is None:
        law, factor, period = state_feedback(feedback), internal, controller_period(scenario, feedback)  # type: ignore
    else:
        factor, period = controller_factor(scenario.simulation, controller.sample_rate)
        law = controller_law(scenario, model, p, start, controller, noise, seed)
    if factor != internal:  # the substeps rule on the loop's own grid
        grid = time_grid(scenario.simulation, scenario.breakpoints, factor)
        substeps = substeps_for(max(start.max_frequency, end.max_frequency if end else 0.0), grid)
        if (factor, substeps) not in cache:
            while len(cache) > 3:
                cache.pop(next(iter(cache)))
            cache[factor, substeps] = grid, model_inputs(scenario, grid, substeps)
        grid, inputs = cache[factor, substeps]
    else:
        grid, inputs = own, grid_inputs(substeps)
    states, inputs = run_closed_loop(scenario, model, grid, inputs, p, start, substeps, forces, law, period)
    return grid, states, inputs


check_public(globals())
