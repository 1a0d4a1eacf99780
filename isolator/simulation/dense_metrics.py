"""Peaks and settling instants of DOP853 runs, found on the dense output rather than at the output samples.

The compiled loop reads the six table signals at ``PROBES`` fixed points of
every step (fractions 1/8 ... 1, :mod:`isolator.numerics.step_plan`) and keeps
per step the largest ``|s|`` and the largest ``|s - final|`` over them. The
steps do not depend on the output samples (breakpoints and the run's end fix
them), so neither do these numbers; from them:

- the peak of a signal: around its largest probe, the signal is evaluated
  from the step's seventh-order polynomial at ``PEAK_POINTS`` points spanning
  the neighbouring probes, and a parabola through the largest three gives the
  maximum (relative error far below 1e-9 for the steps' ``|lambda| h <= 0.9``);
- the settling instant: the last step after the stop with a probe outside the
  band holds the last probe outside; between it and the next probe (inside)
  ``|s - final| - band`` is evaluated at ``CROSSING_POINTS`` points and its last
  zero placed by linear interpolation between the two points around it (to
  about 1e-7 s; the probes are at most 6.25 ms apart).

An excursion past the band that begins and ends between two neighbouring
probes, entirely, is not seen (it would leave the band by less than about
0.2 % of it).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from isolator.model.quasi_static_top import QuasiStaticTop
from isolator.model.variants import Model
from isolator.numerics.dop853_driver import Dop853Driver
from isolator.numerics.step_plan import StepPlan
from isolator.scenario.definitions import Settling
from isolator.simulation.band import Band, as_band
from isolator.simulation.free_tail import FreeTail
from isolator.simulation.settling import SettlingResult, settling_results, unavailable_reason
from isolator.simulation.stepping import check_turn, dense_stepper, signal_width

__all__ = ["CROSSING_POINTS", "PEAK_POINTS", "DenseRuns", "dense_metrics", "run_metrics"]

#: points across the two probe intervals around a signal's largest probe
PEAK_POINTS = 17
#: points across the probe interval in which a signal enters its band for good
CROSSING_POINTS = 33


@dataclass(frozen=True)
class DenseRuns:
    """What the compiled steps give for ``R`` runs of one plan (the last axis of each array).

    Attributes
    ----------
    plan : StepPlan
        With probes.
    slots : ndarray (steps x per_step, 6, R)
        The signals at every step's slots (the probes first).
    peaks, deviations : ndarray (steps, 6, R)
        Per step, max |s| and max |s - final| over its probes.
    polynomials : ndarray (steps, degree + 1, n_states, R)
        Each step's dense output.
    reference : ndarray (R, n_states)
        The state each run's signals are measured from.
    signals : callable
        ``(states (N, n_states), references (N, n_states)) -> (6, N)``.
    width : int
        How many leading states ``signals`` reads (:func:`~isolator.simulation.stepping.signal_width`; 0: all):
        :meth:`at` evaluates the dense output of those only.
    compiled : Dop853Driver, optional
        The compiled loop that stepped the runs: :func:`dense_metrics` then computes in it
        (``cpp/dense_metrics.cpp``, the same rules); else in numpy, here.
    """

    plan: StepPlan
    slots: np.ndarray
    peaks: np.ndarray
    deviations: np.ndarray
    polynomials: np.ndarray
    reference: np.ndarray
    signals: Callable[[np.ndarray, np.ndarray], np.ndarray]
    width: int = 0
    compiled: Dop853Driver | None = None

    @classmethod
    def of_run(cls, plan: StepPlan, stepped: tuple[np.ndarray, ...], reference: np.ndarray,
               model: Model | QuasiStaticTop) -> DenseRuns:
        """One run's (``R`` = 1): ``stepped`` the signals at the slots, the steps' peaks and deviations and their
        dense output as ``DenseStepper.run_slots`` gives them for one run, ``reference`` its start state; computed
        in the compiled loop of ``model`` when it has one."""
        slots, peaks, deviations, polynomials = (a[..., None] for a in stepped)
        return cls(plan, slots, peaks, deviations, polynomials, np.asarray(reference)[None, :], model.variant.signals,
                   signal_width(model), dense_stepper(model).driver)

    def at(self, t: np.ndarray, lane: np.ndarray) -> np.ndarray:
        """The six signals (6, K) of runs ``lane`` (K,) at times ``t`` (K,) [s], from the dense output."""
        step, s = self.plan.locate(t)
        width = self.width or self.polynomials.shape[2]
        one = self.polynomials.shape[-1] == 1  # one run: a contiguous gather
        c = (self.polynomials[:, :, :width, 0][step] if one else
             self.polynomials[step, :, :width, lane])  # (K, degree + 1, states the signals read)
        x = c[:, -1]
        for j in range(c.shape[1] - 2, -1, -1):
            x = c[:, j] + s[:, None] * x
        return self.signals(x, self.reference[lane])

    def probe_values(self, step: np.ndarray) -> np.ndarray:
        """Each signal's values at the probes of its step ``step`` (6, R) [m or rad], (6, R, probes)."""
        per, probes = self.plan.per_step, self.plan.probes
        k, r = _indices(step.shape)
        rows = step[..., None] * per + np.arange(probes)
        return self.slots[rows, k[..., None], r[..., None]]

    def probe_time(self, step: np.ndarray, j: np.ndarray) -> np.ndarray:
        """The time [s] of probe ``j`` (0 .. probes - 1) of step ``step``."""
        plan = self.plan
        return plan.start[step] + plan.length[step] * (j + 1) / plan.probes

    def own_rows(self, values: np.ndarray) -> np.ndarray:
        """From :meth:`at` over points laid out (6, R, K) flat: each signal's own row, (6, R, K)."""
        shape = (6, self.peaks.shape[2], -1)
        return values.reshape(6, *shape)[np.arange(6), np.arange(6)]


def _indices(shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Row and column index arrays of a (signals, runs) shape."""
    return (np.broadcast_to(np.arange(shape[0])[:, None], shape), np.broadcast_to(np.arange(shape[1])[None, :], shape))


def _peak_window(runs: DenseRuns) -> tuple[np.ndarray, np.ndarray]:
    """Each signal's largest probe (6, R) and the times (6, R, PEAK_POINTS) [s] spanning its neighbours."""
    plan = runs.plan
    top = np.max(runs.peaks, axis=0)
    step = np.argmax(runs.peaks, axis=0)
    j = np.argmax(np.abs(runs.probe_values(step)), axis=-1)
    spread = (plan.length[step] / plan.probes)[..., None] * np.linspace(-1.0, 1.0, PEAK_POINTS)
    return top, np.clip(runs.probe_time(step, j)[..., None] + spread, 0.0, plan.end)


def _refined_peak(top: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The largest |s| (6, R) from the probes' ``top`` and |s| at the window's points (6, R, PEAK_POINTS):
    the vertex of a parabola through the largest point and its neighbours."""
    i = np.clip(np.argmax(values, axis=-1), 1, PEAK_POINTS - 2)[..., None]
    a, b, c = (np.take_along_axis(values, i + d, axis=-1)[..., 0] for d in (-1, 0, 1))
    curvature = a - 2.0 * b + c
    with np.errstate(all="ignore"):
        vertex = np.where(curvature < 0.0, b - (a - c) ** 2 / (8.0 * curvature), b)
    best = np.max(values, axis=-1)
    return np.maximum(top, np.maximum(best, np.minimum(vertex, best * (1 + 1e-6))))


def dense_peaks(runs: DenseRuns) -> np.ndarray:
    """max |s| of each signal over each run (6, R), refined about the largest probe."""
    top, t = _peak_window(runs)
    if not np.all(np.isfinite(top)):
        return top
    lanes = np.broadcast_to(np.arange(top.shape[1])[None, :, None], t.shape)
    return _refined_peak(top, np.abs(runs.own_rows(runs.at(t.ravel(), lanes.ravel()))))


def _entry_interval(
    runs: DenseRuns, target: np.ndarray, band: np.ndarray, stop_time: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per signal and run (6, R): the probe interval ``ta`` (outside) .. ``tb`` (inside) [s] of the last
    entry into the band after the stop, whether the signal is outside at or after the stop at all, and
    whether it is still outside at the run's end."""
    plan, per, steps = runs.plan, runs.plan.per_step, runs.plan.steps
    first = int(np.searchsorted(plan.start[:steps], stop_time - 1e-9 * max(1.0, stop_time), side="left"))
    out = runs.deviations[first:steps] > band  # (after, 6, R)
    after = out.any(axis=0)
    last = np.full(band.shape, max(first - 1, 0))  # meaningful where ``after``
    if out.shape[0]:
        last = first + out.shape[0] - 1 - np.argmax(out[::-1], axis=0)
    k, r = _indices(band.shape)
    if first > 0:
        at_stop = np.abs(runs.slots[(first - 1) * per + plan.probes - 1, k, r] - target) > band
    else:
        at_stop = np.abs(target) > band  # the signals start at zero
    outside = np.abs(runs.probe_values(last) - target[..., None]) > band[..., None]
    j = plan.probes - 1 - np.argmax(outside[..., ::-1], axis=-1)
    ta = np.where(after, runs.probe_time(last, j), stop_time)
    nxt_step = np.where(after, np.where(j < plan.probes - 1, last, last + 1), first)
    nxt_j = np.where(after & (j < plan.probes - 1), j + 1, 0)
    at_end = nxt_step >= steps
    tb = np.where(at_end, plan.end, runs.probe_time(np.minimum(nxt_step, steps - 1), nxt_j))
    return ta, tb, after | at_stop, at_end


def _crossing(t: np.ndarray, values: np.ndarray, target: np.ndarray, band: np.ndarray) -> np.ndarray:
    """Where ``|s - target| - band`` at times ``t`` (6, R, points) last falls to zero, interpolated (6, R)."""
    gap = np.abs(values - target[..., None]) - band[..., None]
    outside = gap > 0.0
    i = np.minimum(CROSSING_POINTS - 1 - np.argmax(outside[..., ::-1], axis=-1), CROSSING_POINTS - 2)
    i = np.where(outside.any(axis=-1), i, 0)[..., None]
    g0, g1 = (np.take_along_axis(gap, i + d, axis=-1)[..., 0] for d in (0, 1))
    t0, t1 = (np.take_along_axis(t, i + d, axis=-1)[..., 0] for d in (0, 1))
    with np.errstate(all="ignore"):
        weight = np.clip(np.where(g0 - g1 > 0.0, g0 / (g0 - g1), 0.0), 0.0, 1.0)
    return t0 + (t1 - t0) * weight


def dense_metrics(
    runs: DenseRuns,
    final: np.ndarray | None,
    stop_time: float,
    band: Band,
    hold: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Peaks and settling of ``R`` runs from their dense output.

    In the compiled loop that stepped the runs when there is one (``runs.compiled``); else in numpy: there
    the entry interval is first chosen with the bands of the probes' peaks, and the points of both
    refinements are evaluated in one call; where the refined peaks' bands choose another interval
    (rarely: the band grows by the refinement), its points are evaluated again.

    Parameters
    ----------
    runs : DenseRuns
    final : ndarray (R, 6) or None
        The targets the compiled loop measured the deviations from (None: zero, a carriage never stops).
    stop_time : float
        [s], within the run, or inf.
    band : Band
        The settling band (its half-widths for each run's refined peaks, :meth:`Band.resolve`).
    hold : ndarray (R,)
        [s], as in :func:`isolator.simulation.settling.settling_time`.

    Returns
    -------
    peaks : ndarray (R, 6)
        [m or rad].
    time : ndarray (R, 6)
        Settling time after the stop [s]; NaN where the run does not show it.
    short : ndarray (R, 6)
        How long before the run's end each signal was last outside its band [s].
    """
    if runs.compiled is not None:
        lanes = runs.peaks.shape[2]
        target = np.zeros((lanes, 6)) if final is None else np.asarray(final, dtype=float)
        fixed = (-1.0, np.asarray(band.half_widths, dtype=float)) if band.half_widths is not None else (
            float(band.fraction), np.zeros(6))  # type: ignore[arg-type]  # an own-peak band has its fraction
        return runs.compiled.metrics(runs.plan, runs.slots, runs.peaks, runs.deviations, runs.polynomials,
                                     runs.reference, target, stop_time, fixed, np.asarray(hold, dtype=float))
    bands_of = band.resolve
    top, tp = _peak_window(runs)
    lanes = top.shape[1]
    if not np.isfinite(stop_time) or not np.all(np.isfinite(top)):
        return dense_peaks(runs).T, np.full((lanes, 6), np.nan), np.zeros((lanes, 6))
    target = np.zeros((6, lanes)) if final is None else np.asarray(final, dtype=float).T
    guess = np.asarray(bands_of(top.T), dtype=float).T
    ta, tb, _, _ = _entry_interval(runs, target, guess, stop_time)
    tc = ta[..., None] + (tb - ta)[..., None] * np.linspace(0.0, 1.0, CROSSING_POINTS)
    _, r = _indices(top.shape)
    both = np.concatenate([tp, tc], axis=-1)
    values = runs.own_rows(runs.at(both.ravel(), np.broadcast_to(r[..., None], both.shape).ravel()))
    peaks = _refined_peak(top, np.abs(values[..., :PEAK_POINTS]))
    bands = np.asarray(bands_of(peaks.T), dtype=float).T  # (6, R)
    ta2, tb2, moves, at_end = _entry_interval(runs, target, bands, stop_time)
    at_points = values[..., PEAK_POINTS:]
    again = (ta2 != ta) | (tb2 != tb)
    if again.any():  # the refined band chose another interval: its points
        tc = ta2[..., None] + (tb2 - ta2)[..., None] * np.linspace(0.0, 1.0, CROSSING_POINTS)
        fresh = runs.own_rows(runs.at(tc.ravel(), np.broadcast_to(r[..., None], tc.shape).ravel()))
        at_points = np.where(again[..., None], fresh, at_points)
    crossing = _crossing(tc, at_points, target, bands)
    end = runs.plan.end
    short = np.where(moves, np.where(at_end, 0.0, end - crossing), 0.0)
    time = np.where(moves, crossing - stop_time, 0.0)
    unsettled = moves & (at_end | (short < np.asarray(hold, dtype=float)[None, :]))
    return peaks.T, np.where(unsettled, np.nan, time).T, short.T


def run_metrics(
    runs: DenseRuns,
    final: np.ndarray | None,
    stop_time: float,
    rule: Band | Settling,
    hold: float,
    samples: np.ndarray,
    signals: np.ndarray,
    tail: FreeTail | None = None,
    rest_note: str = "",
) -> dict[str, SettlingResult]:
    """Settling of the six signals of one DOP853 run (``R`` = 1), by name; ``final`` (6,) or None;
    ``signals`` (6, samples) at the output ``samples`` [s] only name the sample where a run turned too far;
    ``tail``, ``rest_note`` as for :func:`~isolator.simulation.settling.settling_results` (``hold`` is then
    not waited)."""
    peaks, times, short = dense_metrics(
        runs, None if final is None else final[None, :], stop_time, as_band(rule), np.array([0.0 if tail else hold]),
    )
    check_turn(peaks[0], samples, signals)
    why = unavailable_reason(runs.plan.end, stop_time)
    return settling_results(times[0], short[0], peaks[0], final is not None, rule, why, tail, rest_note)
