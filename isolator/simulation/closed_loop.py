"""Runs with a sampled controller: RK4 interval by interval, the controller ticking at its rate."""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from isolator.errors import ParameterError
from isolator.model.equilibrium import Equilibrium
from isolator.model.parameters import ParameterLayout
from isolator.model.variants import Model
from isolator.scenario.definitions import Scenario
from isolator.simulation.actuation import ForceHistory, applied_forces
from isolator.simulation.stepping import rk4_stepper
from isolator.simulation.time_grid import TimeGrid, internal_rate, stage_times

__all__ = ["FeedbackLaw", "controller_period", "run_closed_loop"]


class FeedbackLaw(Protocol):
    """A sampled controller the simulation runs (e.g. :class:`controllers.feedback.DiscreteLaw`).

    Attributes
    ----------
    sample_rate : float
        [Hz]; must divide the rate the simulation steps at (its output sample rate, raised by a whole
        factor to 1 kHz or more: :func:`isolator.simulation.time_grid.internal_rate`).
    """

    sample_rate: float

    def reset(self) -> None:
        """Forget the controller's state (called at the start of a run)."""

    def __call__(self, t: float, measurement: np.ndarray) -> np.ndarray:
        """Commands [N] per actuator at tick ``t`` [s] from the measured table state (12,): displacement
        [m] and rotation vector [rad] from the initial equilibrium, velocity [m/s] and angular velocity
        [rad/s], world axes. Held until the next tick."""

    def final(self, passive: np.ndarray) -> np.ndarray:
        """The six signals' closed-loop final value given the passive one (the settling reference)."""


def controller_period(scenario: Scenario, feedback: FeedbackLaw) -> int:
    """Nodes of the regular internal grid per controller tick."""
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


def run_closed_loop(
    scenario: Scenario,
    layout: ParameterLayout,
    model: Model,
    grid: TimeGrid,
    grid_inputs: np.ndarray,
    p: np.ndarray,
    start: Equilibrium,
    substeps: int,
    forces: ForceHistory | None,
    feedback: FeedbackLaw,
) -> tuple[np.ndarray, np.ndarray]:
    """Step interval by interval, the controller ticking at its rate.

    Parameters
    ----------
    grid_inputs : ndarray (intervals, stages, inputs)
        The model's inputs at every RK4 stage of the grid (not changed; the actuator forces are
        filled in a copy as the run goes).
    forces : ForceHistory, optional
        The feedforward command, added to the controller's before saturation and lag.

    Returns
    -------
    states : ndarray (intervals, n_states)
        After each interval (NaN from the first non-finite one on).
    inputs : ndarray (intervals, stages, inputs)
        With the applied forces.
    """
    period = controller_period(scenario, feedback)
    inputs = grid_inputs.copy()  # the actuator forces are filled in as the run goes
    acts = layout.actuator_slice
    times, mid = stage_times(grid, substeps)
    # the feedforward command before saturation and lag
    commanded = None if forces is None else forces.command(times.ravel(), mid.ravel()).reshape(*times.shape, -1)
    regular = grid.regular
    ticks = regular & ((np.cumsum(regular) - 1) % period == 0)
    stepper = rk4_stepper(model, substeps)
    steps = np.diff(grid.nodes)
    n_a = layout.n_actuators
    u = np.zeros(n_a)
    lag = np.zeros(n_a)
    x = start.state.copy()
    out = np.empty((steps.size, x.size))
    feedback.reset()
    motion = np.zeros(12)
    limits = np.array([a.max_force for a in scenario.actuators])
    lagged = any(a.bandwidth is not None for a in scenario.actuators)
    for i, h in enumerate(steps):
        if ticks[i]:
            u = np.asarray(feedback(float(grid.nodes[i]), motion), dtype=float).reshape(n_a)
        command = u if commanded is None else commanded[i] + u
        if lagged:
            applied = applied_forces(scenario, np.broadcast_to(command, (times.shape[1], n_a)), times[i], lag)
            lag = applied[-1]
        else:  # what applied_forces does without a lag, without its per-call overhead
            applied = np.clip(command, -limits, limits)
        inputs[i, :, acts] = applied
        x, motion = stepper.step(x, inputs[i], float(h), p, start.state)
        out[i] = x
        if not np.all(np.isfinite(x)):
            out[i:] = np.nan
            break
    return out, inputs
