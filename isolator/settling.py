"""The paper's 5 % settling time, made exact (``docs/scenario-format.md``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .scenario import SIGNALS, Settling

__all__ = ["SettlingResult", "settling_time"]

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
    if math.isinf(stop_time):
        return None, "a carriage never stops (sine profile): no settling time"
    if stop_time > t[-1]:
        return None, f"the run ends at {t[-1]:g} s, before the carriages stop at {stop_time:g} s"
    after = t >= stop_time - 1e-12
    outside = np.abs(s[after] - final) > band
    if not outside.any():
        return 0.0, ""
    last = t[after][np.nonzero(outside)[0][-1]]
    if last >= t[-1] or t[-1] - last < hold:
        return None, (
            f"still outside the band {t[-1] - last:.3g} s before the run ends; "
            "lengthen simulation.duration"
        )
    return float(last - stop_time), ""


def settling_metrics(
    t: np.ndarray,
    signals: np.ndarray,
    final: np.ndarray | None,
    stop_time: float,
    settling: Settling,
    hold: float = 0.0,
) -> dict[str, SettlingResult]:
    """Settling of each of the six table signals, keyed by name (``SIGNALS``)."""
    out: dict[str, SettlingResult] = {}
    for i, name in enumerate(SIGNALS):
        peak = float(np.max(np.abs(signals[i]))) if signals.shape[1] else 0.0
        band = settling.band(name, peak)
        if final is not None and settling.tolerance is None and peak <= MOTION_FLOOR:
            time, reason = 0.0, "does not move"
        else:
            target = 0.0 if final is None else float(final[i])
            time, reason = settling_time(t, signals[i], target, stop_time, max(band, 1e-300), hold)
        out[name] = SettlingResult(time, peak, band, reason)
    return out
