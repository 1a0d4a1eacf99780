"""Window settling of a single move: how long after the stop each ``[[windows]]`` point stays inside its
absolute window (``docs/scenario-format.md``, "Windows at points and step-and-settle sequences").

The rule is read on a grid of at least 1 kHz from the integrator's dense output (or the RK4 runs' internal
grid), not on the output samples, and the last exit is refined by linear interpolation between the two grid
times around it, so the window settling time does not depend on the output sample rate.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from isolator.scenario.definitions import Scenario
from isolator.scenario.readable import length_text
from isolator.scenario.windows import Window
from isolator.simulation.free_tail import FreeTail, TailVerdict
from isolator.simulation.points import PointSet

__all__ = ["WindowResult", "moves_per_hour", "plot_windows", "run_points", "window_exit", "window_result"]


def moves_per_hour(move_time: float | None, window_settling: float | None) -> float | None:
    """Moves per hour [1/h] of a machine that repeats a move of ``move_time`` [s] (first carriage's start to the
    stop) and waits ``window_settling`` [s] after each until every window holds: ``3600 / (move_time +
    window_settling)``; None when either is unknown or the sum is not > 0."""
    if move_time is None or window_settling is None:
        return None
    cycle = move_time + window_settling
    return 3600.0 / cycle if math.isfinite(cycle) and cycle > 0 else None


def window_exit(
    t: np.ndarray, deviation: np.ndarray, half_width: float | np.ndarray, stop_time: float, hold: float = 0.0
) -> tuple[float | None, str]:
    """Window settling time [s] of deviations (axes, N) at times (N,): the last time at or after
    ``stop_time`` at which ``|deviation| > half_width`` on any axis (one half-width [m], or one per axis),
    minus ``stop_time`` (0 if never outside after the stop), with the exit interpolated linearly between the
    grid times around it.

    Returns the time and "" , or None and why the run cannot show it: the carriages never stop, the run
    ends before the stop, the point is outside at the end, or inside for less than ``hold`` [s] (the
    slowest mode's period) before the run ends.
    """
    t = np.asarray(t, dtype=float)
    dev = np.atleast_2d(np.asarray(deviation, dtype=float))
    if not math.isfinite(stop_time):
        return None, "the carriages never stop"
    if t[-1] < stop_time:
        return None, "the run ends before the carriages stop"
    first = int(np.searchsorted(t, stop_time - 1e-12))
    after = dev[:, first:]
    widths = np.broadcast_to(np.asarray(half_width, dtype=float), (dev.shape[0],))
    outside = np.any(np.abs(after) > widths[:, None], axis=0)
    if not outside.any():
        return 0.0, ""
    if outside[-1]:
        return None, "outside the window at the end of the run (longer duration needed)"
    k = first + int(np.flatnonzero(outside)[-1])
    exit_time = float(t[k])
    for d0, d1, width in zip(dev[:, k], dev[:, k + 1], widths, strict=True):
        if abs(d0) > width:
            edge = math.copysign(width, d0)
            exit_time = max(exit_time, float(t[k] + (t[k + 1] - t[k]) * (d0 - edge) / (d0 - d1)))
    exit_time = max(exit_time, stop_time)
    if t[-1] - exit_time < hold * (1 - 1e-9):
        return None, f"inside the window for less than the slowest period ({hold:.3g} s) before the run ends"
    return exit_time - stop_time, ""


@dataclass(frozen=True)
class WindowResult:
    """Each window's settling time after the stop, and the deviations it was read on.

    Attributes
    ----------
    windows : tuple of Window
        In ``[[windows]]`` order.
    settling_time : tuple of float or None
        Per window [s]; None where the run cannot show it (see ``reasons``).
    reasons : tuple of str
    t : ndarray (M,)
        The >= 1 kHz grid the rule was read on [s].
    deviations : tuple of ndarray (listed axes, M)
        Each window's point deviation from its settled position on the listed axes [m].
    """

    windows: tuple[Window, ...]
    settling_time: tuple[float | None, ...]
    reasons: tuple[str, ...]
    t: np.ndarray
    deviations: tuple[np.ndarray, ...]

    @property
    def settling_time_max(self) -> float | None:
        """The largest window settling time [s]; None if any window's is unknown (or there are none)."""
        if not self.settling_time or any(v is None for v in self.settling_time):
            return None
        return max(v for v in self.settling_time if v is not None)

    def to_dict(self) -> dict[str, Any]:
        """The JSON keys ``window_settling_time`` (list, ``[[windows]]`` order), ``..._max`` and notes."""
        out: dict[str, Any] = {
            "window_settling_time": list(self.settling_time),
            "window_settling_time_max": self.settling_time_max,
            "window_notes": {f"windows[{i}]": r for i, r in enumerate(self.reasons) if r},
        }
        if any(w.random is not None for w in self.windows):
            out["window_random"] = [w.random_margins for w in self.windows]
        return out

    def summary_lines(self) -> list[str]:
        lines = []
        for i, (w, st, why) in enumerate(zip(self.windows, self.settling_time, self.reasons, strict=True)):
            value = f"{st:.4g} s after the stop" if st is not None else f"not available ({why})"
            room = "" if not w.margin else f", less {w.random:g} sigma of random motion: ±" + ", ".join(
                f"{length_text(h)} on {a}" for a, h in zip(w.axes, w.half_widths, strict=True))
            lines.append(f"window {i} ({w.point}, ±{length_text(w.translation)} on {','.join(w.axes)}{room}): {value}")
        return lines


def _after_the_end(w: Window, verdict: TailVerdict, outside_at_end: bool, note: str) -> str:
    """Why a window shows no settling time, from the free motion after the run's end (its worst axis)."""
    k = int(np.argmax(verdict.excess))
    axis, over = w.axes[k], length_text(float(verdict.excess[k]))
    if not math.isfinite(verdict.enters[k]):
        return (f"the point comes to rest {length_text(abs(float(verdict.offset[k])))} from its settled position "
                f"on {axis}, outside the window{': ' + note if note else ''}; a longer run cannot help")
    where = "is still outside the window when the run ends" if outside_at_end else "leaves the window again"
    return (f"{where} at {verdict.end:.4g} s, by up to {over} on {axis} (at {verdict.when[k]:.4g} s), and stays "
            f"inside from {verdict.enters[k]:.4g} s by the linear model about the final rest; lengthen "
            f"simulation.duration to {verdict.needed(k):g} s or more")


def window_result(
    windows: tuple[Window, ...],
    points: PointSet,
    stop_time: float,
    hold: float,
    fine: Callable[[], tuple[np.ndarray, np.ndarray]],
    tail: FreeTail | None = None,
    note: str = "",
) -> WindowResult:
    """The window settling of a run whose states on a >= 1 kHz grid ``fine()`` gives (times, states); with
    the free motion after the run's end (``tail``), a window settling time stands only if the point stays
    inside the window after it (``hold`` not waited; ``note``: what keeps the table off its final rest)."""
    t, states = fine()
    moved = points.displacements(states)
    times, reasons, deviations = [], [], []
    jacobian = None if tail is None else points.jacobian(tail.rest - tail.shift)
    for w in windows:
        i, axes = points.index(w.point), list(w.axis_indices)
        if points.settled is None:
            deviation = moved[i, axes]
            st, why = None, "the carriages never stop"
        else:
            deviation = moved[i, axes] - points.settled[i, axes, None]
            st, why = window_exit(t, deviation, w.half_widths, stop_time, 0.0 if tail else hold)
            if jacobian is not None and tail is not None and (st is not None or why.startswith("outside")):
                verdict = tail.outputs(jacobian[i, axes]).judge(w.half_widths)
                if verdict.leaves.any() or st is None:
                    st, why = None, _after_the_end(w, verdict, st is None, note)
        times.append(st)
        reasons.append(why)
        deviations.append(deviation)
    return WindowResult(windows, tuple(times), tuple(reasons), np.asarray(t), tuple(deviations))


def plot_windows(result: WindowResult, stop_time: float, title: str) -> Any:
    """One panel per window: the point's deviation from its settled position on each listed axis [nm]
    against time, the window shaded, the stop and the settled time marked."""
    import matplotlib.pyplot as plt

    n = len(result.windows)
    fig, axes = plt.subplots(n, 1, figsize=(10, 3.2 * n + 0.6), squeeze=False, sharex=True,
                             constrained_layout=True)
    for ax, w, dev, st in zip(axes[:, 0], result.windows, result.deviations, result.settling_time, strict=True):
        for axis, row in zip(w.axes, dev, strict=True):
            ax.plot(result.t, row * 1e9, lw=1.0, label=f"{w.point}:{axis}")
        h = w.translation * 1e9
        ax.axhspan(-h, h, color="tab:green", alpha=0.15, lw=0, label=f"window ±{length_text(w.translation)}")
        if w.margin:
            room = float(np.min(w.half_widths)) * 1e9
            ax.axhspan(-room, room, color="tab:green", alpha=0.2, lw=0,
                       label=f"less {w.random:g} sigma of random motion: ±{length_text(room * 1e-9)}")
        if math.isfinite(stop_time):
            ax.axvline(stop_time, color="0.5", ls=":", lw=1, label="carriages stop")
            if st is not None:
                ax.axvline(stop_time + st, color="tab:red", ls="--", lw=1,
                           label=f"settled: {st:.3g} s after the stop")
        peak = max(float(np.max(np.abs(dev))) * 1e9, h) if dev.size else h
        ax.set_ylim(-min(peak, 20 * h) * 1.1, min(peak, 20 * h) * 1.1)
        ax.set_ylabel(f"{w.point} deviation [nm]")
        ax.set_title(f"window at {w.point} (deviation from its settled position; axis limited to 20 x the window)",
                     fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    if math.isfinite(stop_time) and result.t.size:  # before the stop the point travels with the table's tilt
        axes[-1, 0].set_xlim(max(float(result.t[0]), stop_time - 0.5), float(result.t[-1]))
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title)
    return fig


def run_points(
    scenario: Scenario, kind: str, start: np.ndarray, end: np.ndarray | None, stop_time: float, hold: float,
    fine: Callable[[], tuple[np.ndarray, np.ndarray]], free: tuple[FreeTail | None, str] = (None, ""),
) -> tuple[PointSet, Callable[[], WindowResult] | None]:
    """A run's points (from its initial state ``start`` and final rest state ``end``) and, with
    ``[[windows]]``, its window settling computed on first use (``free``: the free motion after the run's
    end and the note of :func:`~isolator.simulation.tail_check.run_tail`)."""
    points = PointSet.of(scenario, kind, start, end)
    if not scenario.windows:
        return points, None
    return points, lambda: window_result(scenario.windows, points, stop_time, hold, fine, *free)
