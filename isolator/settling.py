"""The paper's 5 % settling time, made exact (``docs/scenario-format.md``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .scenario import SIGNALS, Settling

__all__ = ["SettlingResult", "settling_metrics", "settling_time", "settling_times", "signal_peaks"]

#: peaks below this are numerical noise: such a signal does not move [m or rad]
MOTION_FLOOR = 1e-13


@dataclass(frozen=True)
class SettlingResult:
    """Settling of one signal.

    Attributes
    ----------
    time : float or None
        Settling time after the stop [s]; None when the run cannot show it.
    peak : float
        max |s| over the run [m or rad].
    band : float
        Half-width of the band around ``final`` [m or rad].
    reason : str
        Why ``time`` is None, or a remark ("" when settled normally).
    """

    time: float | None
    peak: float
    band: float
    reason: str = ""


def settling_time(
    t: np.ndarray,
    s: np.ndarray,
    final: float,
    stop_time: float,
    band: float,
    hold: float = 0.0,
) -> tuple[float | None, str]:
    """Settling time of one signal.

    Parameters
    ----------
    t : ndarray
        Sample times [s].
    s : ndarray
        Signal [m or rad].
    final : float
        Static equilibrium value with the carriages at their final positions.
    stop_time : float
        When the last carriage stops [s].
    band : float
        Half-width of the band [m or rad], > 0.
    hold : float
        How long [s] the signal must be seen inside the band before the run
        ends for the result to count (e.g. one period of the slowest mode).

    Returns
    -------
    time : float or None
        The last time at or after ``stop_time`` at which ``|s - final| > band``,
        minus ``stop_time``; 0 if inside from the stop on; None if the run does
        not show the signal settled.
    reason : str
        Why the time is None ("" otherwise).
    """
    return settling_times(t, np.asarray(s)[None, :], np.array([final]), stop_time, np.array([band]), hold)[0]


def settling_times(
    t: np.ndarray,
    signals: np.ndarray,
    final: np.ndarray,
    stop_time: float,
    band: np.ndarray,
    hold: float = 0.0,
) -> list[tuple[float | None, str]]:
    """:func:`settling_time` of several signals (rows of ``signals``) at once.

    Parameters
    ----------
    t : ndarray (samples,)
        [s].
    signals : ndarray (k, samples)
        [m or rad].
    final, band : ndarray (k,)
        Final values and band half-widths (> 0) [m or rad].
    stop_time, hold : float
        [s], as in :func:`settling_time`.
    """
    k = signals.shape[0]
    if math.isinf(stop_time):
        return [(None, "a carriage never stops (sine profile): no settling time")] * k
    if stop_time > t[-1]:
        return [(None, f"the run ends at {t[-1]:g} s, before the carriages stop at {stop_time:g} s")] * k
    first = int(np.searchsorted(t, stop_time - 1e-12, side="left"))
    outside = np.abs(signals[:, first:] - np.asarray(final, float)[:, None]) > np.asarray(band, float)[:, None]
    any_outside = outside.any(axis=1)
    last = t[first:][outside.shape[1] - 1 - np.argmax(outside[:, ::-1], axis=1)] if outside.shape[1] else t[:0]
    out: list[tuple[float | None, str]] = []
    for i in range(k):
        if not any_outside[i]:
            out.append((0.0, ""))
        elif last[i] >= t[-1] or t[-1] - last[i] < hold:
            out.append((None, f"still outside the band {t[-1] - last[i]:.3g} s before the run ends; "
                              "lengthen simulation.duration"))
        else:
            out.append((float(last[i] - stop_time), ""))
    return out


def signal_peaks(signals: np.ndarray) -> np.ndarray:
    """max |s| of each row of ``signals`` (0 for no samples)."""
    if not signals.shape[1]:
        return np.zeros(signals.shape[0])
    return np.maximum(signals.max(axis=1), -signals.min(axis=1))


def settling_metrics(
    t: np.ndarray,
    signals: np.ndarray,
    final: np.ndarray | None,
    stop_time: float,
    settling: Settling,
    hold: float = 0.0,
    peaks: np.ndarray | None = None,
) -> dict[str, SettlingResult]:
    """Settling of each of the six table signals, keyed by name (``SIGNALS``).

    ``peaks`` (max |signal| per row), when the caller has them already.
    """
    if peaks is None:
        peaks = signal_peaks(signals)
    bands = np.array([settling.band(name, float(peak)) for name, peak in zip(SIGNALS, peaks, strict=True)])
    still = np.zeros(len(SIGNALS), dtype=bool)
    if final is not None and settling.tolerance is None:
        still = peaks <= MOTION_FLOOR
    target = np.zeros(len(SIGNALS)) if final is None else np.asarray(final, dtype=float)
    moving = np.nonzero(~still)[0]
    times = settling_times(t, signals[moving], target[moving], stop_time, np.maximum(bands[moving], 1e-300), hold)
    results = dict(zip(moving.tolist(), times, strict=True))
    out: dict[str, SettlingResult] = {}
    for i, name in enumerate(SIGNALS):
        time, reason = results.get(i, (0.0, "does not move"))
        out[name] = SettlingResult(time, float(peaks[i]), float(bands[i]), reason)
    return out
