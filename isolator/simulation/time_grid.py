"""The integration grid of a run and the model's inputs on it.

The time grid RK4 steps on (runs with actuator forces or feedback, or with
breakpoints so dense that RK4 is cheaper than DOP853) is a regular grid at the
*internal rate* -- the output sample rate times the least whole number that
brings it to ``INTERNAL_RATE`` or more, so every output sample is a node --
with the profiles' breakpoints and the run's end (``simulation.duration``)
added, so no step straddles a jump in a carriage's acceleration. Metrics are
taken on all its nodes, so they do not depend on the output rate (exactly so
for output rates that divide ``INTERNAL_RATE``: 5, 50, 1000 Hz give one
grid). The carriages' coordinates are evaluated (in numpy) at every stage time
with the polynomial piece of the interval, i.e. one-sided at breakpoints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from isolator.model.parameters import ParameterLayout
from isolator.scenario.definitions import Scenario, SimulationSettings

__all__ = [
    "INTERNAL_RATE",
    "TimeGrid",
    "grid_breakpoints",
    "inputs_at",
    "internal_rate",
    "layout_inputs",
    "model_inputs",
    "stage_times",
    "time_grid",
]

#: the least rate [Hz] of the grid RK4 steps on; the output rate is raised by a whole factor to reach it
INTERNAL_RATE = 1000.0


@dataclass(frozen=True)
class TimeGrid:
    """Integration grid.

    Attributes
    ----------
    nodes : ndarray
        Grid times [s], increasing, from 0 to the duration.
    is_sample : ndarray of bool
        Which nodes are output samples.
    is_regular : ndarray of bool, optional
        Which nodes are on the regular grid at the internal rate (not breakpoints or the end);
        None: the samples.
    """

    nodes: np.ndarray
    is_sample: np.ndarray
    is_regular: np.ndarray | None = None

    @property
    def regular(self) -> np.ndarray:
        """Which nodes are on the regular internal grid."""
        return self.is_sample if self.is_regular is None else self.is_regular

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
    inside = np.unique(np.array([b for b in breakpoints if 0.0 < b < settings.duration], dtype=float))
    if inside.size:
        index = np.clip(np.rint(inside * settings.sample_rate).astype(int), 0, samples.size - 1)
        nearest = samples[index]
        tolerance = 1e-9 * np.maximum(1.0, inside)
        # a breakpoint with another within the tolerance keeps its time: snapping would merge the two
        # and drop the short phase between them (an impulsive move)
        crowded = np.zeros(inside.size, bool)
        crowded[1:] |= np.diff(inside) <= 2 * tolerance[1:]
        crowded[:-1] |= np.diff(inside) <= 2 * tolerance[:-1]
        inside = np.where((np.abs(nearest - inside) <= tolerance) & ~crowded, nearest, inside)
    return np.unique(inside)


def internal_rate(settings: SimulationSettings) -> tuple[float, int]:
    """The rate [Hz] RK4 steps at and the nodes per output interval (see the module's description)."""
    factor = max(1, math.ceil(INTERNAL_RATE / settings.sample_rate * (1 - 1e-12)))
    return settings.sample_rate * factor, factor


def time_grid(settings: SimulationSettings, breakpoints: tuple[float, ...], factor: int | None = None) -> TimeGrid:
    """The regular grid at the internal rate (holding the output samples) merged with the
    breakpoints and the run's end [s]; ``factor``: the output rate times this whole number instead."""
    samples = settings.sample_times()
    rate, factor = internal_rate(settings) if factor is None else (settings.sample_rate * factor, factor)
    count = int(np.floor(settings.duration * rate * (1 + 1e-12))) + 1
    regular = np.arange(count) / rate
    regular[::factor][: samples.size] = samples[: regular[::factor].size]  # the samples' own times
    flags = np.zeros(count, bool)
    flags[: (samples.size - 1) * factor + 1 : factor] = True
    extra = grid_breakpoints(settings, breakpoints)
    if extra.size:  # within round-off of a regular node: that node (unless another breakpoint is as near)
        index = np.clip(np.rint(extra * rate).astype(int), 0, count - 1)
        near = np.abs(regular[index] - extra) <= 1e-9 * np.maximum(1.0, extra)
        near[1:] &= np.diff(extra) > 2e-9 * np.maximum(1.0, extra[1:])
        near[:-1] &= np.diff(extra) > 2e-9 * np.maximum(1.0, extra[:-1])
        extra = np.unique(np.where(near, regular[index], extra))
    if settings.duration > regular[-1] * (1 + 1e-12) + 1e-12:
        extra = np.append(extra, settings.duration)
    extra = extra[~np.isin(extra, regular)]
    nodes = np.concatenate([regular, extra])
    is_sample = np.concatenate([flags, np.zeros(extra.size, bool)])
    is_regular = np.concatenate([np.ones(count, bool), np.zeros(extra.size, bool)])
    order = np.argsort(nodes, kind="stable")
    return TimeGrid(nodes[order], is_sample[order], is_regular[order])


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
    return layout_inputs(scenario, ParameterLayout.of(scenario), times, mid)


def layout_inputs(scenario: Scenario, layout: ParameterLayout, times: np.ndarray, mid: np.ndarray) -> np.ndarray:
    """:func:`inputs_at` with the scenario's layout already made (a bending top's takes a while)."""
    n = len(scenario.carriages)
    out = np.zeros((*times.shape, layout.input_size))
    for i, carriage in enumerate(scenario.carriages):
        q, v, a = carriage.profile.evaluate(times, mid)
        out[..., i] = q
        out[..., n + i] = v
        out[..., 2 * n + i] = a
    if layout.ground and scenario.ground is not None:
        out[..., layout.ground_slice] = scenario.ground.displacement(times, mid)
    return out
