"""The integration grid of a run and the model's inputs on it.

The time grid is the union of the output sample times and the profiles'
breakpoints, so no step straddles a jump in a carriage's acceleration. The
carriages' coordinates are evaluated (in numpy) at every stage time with the
polynomial piece of the interval, i.e. one-sided at breakpoints.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from isolator.model.parameters import ParameterLayout
from isolator.scenario.definitions import Scenario, SimulationSettings

__all__ = ["TimeGrid", "grid_breakpoints", "inputs_at", "model_inputs", "stage_times", "time_grid"]


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
    then zero actuator forces (see :class:`isolator.model.parameters.ParameterLayout`).

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
