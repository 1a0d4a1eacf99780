"""Where the fixed DOP853 steps fall: equal steps between breakpoints, and the samples each one interpolates."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from isolator.numerics.dop853_tableau import STAGES, dop853_tableau

__all__ = ["PROBES", "TAIL", "StepPlan", "step_plan"]

#: the plans' arrays are padded to a whole number of these steps (the shorter call of the casadi-graph form)
TAIL = 16
#: fixed points per step at which the compiled loop takes the peaks (and the largest deviation from a
#: target): at fractions 1/PROBES, 2/PROBES, ..., 1 of every step, whatever the output samples are
PROBES = 8


@dataclass(frozen=True)
class StepPlan:
    """Where the steps fall and which samples each one interpolates.

    Attributes
    ----------
    start : ndarray (steps,)
        Step start times [s].
    length : ndarray (steps,)
        Step lengths [s].
    first : ndarray (steps,)
        1.0 where the step starts a segment (after a breakpoint): its first
        stage is evaluated afresh rather than taken from the previous step's end.
    fraction : ndarray (steps, per_step)
        Fractions of the step at which signals are read; -1 marks an unused slot. The first
        ``probes`` slots of every step are the probes ``1/probes, ..., 1`` (the peaks are taken
        over them only, so that they do not depend on the output samples); the output samples follow.
    sample_slots : ndarray (samples - 1,)
        Index into the flattened (steps x per_step) outputs of each sample after the first.
    steps : int
        Steps that advance time; the arrays are padded with empty steps (length 0)
        to a whole number of ``TAIL`` steps (for the casadi-graph form of the steps).
    probes : int
        Probe slots at the start of every step's row (0: the peaks are over the samples).
    """

    start: np.ndarray
    length: np.ndarray
    first: np.ndarray
    fraction: np.ndarray
    sample_slots: np.ndarray
    steps: int
    probes: int = 0

    @property
    def end(self) -> float:
        """When the last step ends [s]."""
        return float(self.start[self.steps - 1] + self.length[self.steps - 1]) if self.steps else 0.0

    def probes_only(self) -> StepPlan:
        """The same steps reading the probes alone (no output samples): for runs whose metrics come from
        the probes and the dense output only (a batch's), the loop then evaluates the signals at
        ``probes`` slots per step instead of ``per_step``."""
        width = max(self.probes, 1)
        return StepPlan(self.start, self.length, self.first, np.ascontiguousarray(self.fraction[:, :width]),
                        np.zeros(0, dtype=int), self.steps, self.probes)

    def probe_times(self) -> np.ndarray:
        """The probes' times [s], (steps, probes)."""
        j = np.arange(1, self.probes + 1) / max(self.probes, 1)
        return self.start[: self.steps, None] + self.length[: self.steps, None] * j[None, :]

    def locate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The step holding each time ``t`` [s] (within the run) and the fraction of it."""
        t = np.asarray(t, dtype=float)
        step = np.clip(np.searchsorted(self.start[: self.steps], t, side="right") - 1, 0, self.steps - 1)
        length = self.length[step]
        return step, np.clip((t - self.start[step]) / np.where(length > 0, length, 1.0), 0.0, 1.0)

    @property
    def per_step(self) -> int:
        return int(self.fraction.shape[1])

    @property
    def evaluations(self) -> int:
        """Right-hand-side evaluations of a run."""
        return int(self.steps * (STAGES - 1) + np.count_nonzero(self.first[: self.steps]))

    def stage_times(self) -> tuple[np.ndarray, np.ndarray]:
        """Every step's stage times and its midpoint (which selects the profile piece) [s],
        each (steps, stages)."""
        c = dop853_tableau().c
        times = self.start[:, None] + self.length[:, None] * c[None, :]
        mid = np.broadcast_to((self.start + self.length / 2)[:, None], times.shape)
        return times, mid


def step_plan(
    samples: np.ndarray, breakpoints: np.ndarray, max_step: float, end: float | None = None, probes: int = 0
) -> StepPlan:
    """Equal steps of at most ``max_step`` [s] in every segment between breakpoints.

    Parameters
    ----------
    samples : ndarray
        Output times [s], increasing, from 0, none after ``end``.
    breakpoints : ndarray
        Times [s] inside the run where an input is not smooth.
    max_step : float
        [s], > 0.
    end : float, optional
        When the run ends [s] (default: the last sample).
    probes : int
        Probe slots per step (:attr:`StepPlan.probes`).
    """
    end = float(samples[-1]) if end is None else float(end)
    edges = np.unique(np.concatenate([[0.0], breakpoints[(breakpoints > 0) & (breakpoints < end)], [end]]))
    counts = np.maximum(1, np.ceil(np.diff(edges) / max_step - 1e-9).astype(int))
    lengths = np.diff(edges) / counts
    seg = np.repeat(np.arange(counts.size), counts)
    index = np.arange(seg.size) - np.repeat(np.cumsum(counts) - counts, counts)
    start = edges[seg] + index * lengths[seg]
    length = lengths[seg]
    first = index == 0
    stop = np.append(start[1:], end)
    # a sample belongs to the step it ends or lies inside: start < t <= stop (the first sample is the initial state)
    owner = np.clip(np.searchsorted(stop, samples[1:] - 1e-12 * max(1.0, end), side="left"), 0, start.size - 1)
    counts_per = np.bincount(owner, minlength=start.size)
    per_step = max(1, probes + int(counts_per.max(initial=1)))
    per_step = 4 * math.ceil(per_step / 4)  # fewer variants of the casadi-graph form
    rank = probes + np.arange(owner.size) - np.repeat(np.cumsum(counts_per) - counts_per, counts_per)
    steps = start.size
    padded = TAIL * math.ceil(steps / TAIL)
    fraction = np.full((padded, per_step), -1.0)
    fraction[:steps, :probes] = np.arange(1, probes + 1) / max(probes, 1)
    fraction[owner, rank] = np.clip((samples[1:] - start[owner]) / length[owner], 0.0, 1.0)
    pad = padded - steps
    start = np.concatenate([start, np.full(pad, end)])
    length = np.concatenate([length, np.zeros(pad)])
    first = np.concatenate([first, np.ones(pad, dtype=bool)]).astype(float)
    return StepPlan(start, length, first, fraction, owner * per_step + rank, steps, probes)
