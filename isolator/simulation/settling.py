"""The paper's 5 % settling time, made exact (``docs/scenario-format.md``)."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import SIGNALS, Settling
from isolator.simulation.band import MOTION_FLOOR, Band, as_band
from isolator.simulation.free_tail import FreeTail

__all__ = [
    "MOTION_FLOOR",
    "Band",
    "SettlingResult",
    "judged_times",
    "last_outside",
    "settling_metrics",
    "settling_results",
    "settling_time",
    "settling_times",
    "signal_bands",
    "signal_peaks",
    "signal_settling",
    "still_signals",
    "unavailable_reason",
]


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


#: the dataclass's own ``__init__``, before ``check_public`` wraps it with the public arguments' checks
_RESULT_INIT = SettlingResult.__init__


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
    t, s = _samples(t, "t"), _samples(s, "s")
    if s.size != t.size:
        raise ParameterError(f"s: {s.size} samples for the {t.size} times of t (one per time)")
    for name, value in (("final", final), ("stop_time", stop_time), ("band", band), ("hold", hold)):
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or math.isnan(value):
            raise ParameterError(f"{name}: must be a number, got {value!r}")
    if not (math.isfinite(band) and band > 0):
        raise ParameterError(f"band: must be a finite half-width > 0 [m or rad], got {band!r}")
    if not (math.isfinite(hold) and hold >= 0):
        raise ParameterError(f"hold: must be a finite time >= 0 [s], got {hold!r}")
    return settling_times(t, s[None, :], np.array([float(final)]), float(stop_time), np.array([float(band)]),
                          float(hold))[0]


def _samples(value: object, name: str) -> np.ndarray:
    """A 1-D array of numbers with at least one, or a ParameterError naming ``name``."""
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}: must be a 1-D array of numbers, got {type(value).__name__}") from None
    if out.ndim != 1 or out.size == 0:
        raise ParameterError(f"{name}: must be a 1-D array of numbers, got shape {out.shape}")
    return out


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
    why = _unavailable(t, stop_time)
    if why:
        return [(None, why)] * k
    times, short = last_outside(t, signals, final, stop_time, band, hold)
    return [(None, _outside(short[i])) if math.isnan(times[i]) else (float(times[i]), "") for i in range(k)]


def _unavailable(t: np.ndarray, stop_time: float) -> str:
    """Why a run over times ``t`` [s] shows no settling at all ("" when it can)."""
    return unavailable_reason(float(t[-1]), stop_time)


def unavailable_reason(end: float, stop_time: float) -> str:
    """Why a run ending at ``end`` [s] shows no settling at all ("" when it can)."""
    if math.isinf(stop_time):
        return "a carriage never stops (sine profile): no settling time"
    if stop_time > end:
        return f"the run ends at {end:g} s, before the carriages stop at {stop_time:g} s"
    return ""


def _outside(short: float) -> str:
    return f"still outside the band {short:.3g} s before the run ends; lengthen simulation.duration"


def last_outside(
    t: np.ndarray,
    signals: np.ndarray,
    final: np.ndarray,
    stop_time: float,
    band: np.ndarray,
    hold: float | np.ndarray = 0.0,
    interpolate: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """The settling rule on stacked signals: the core of :func:`settling_time`.

    Parameters
    ----------
    t : ndarray (samples,)
        [s]; the run must reach ``stop_time`` (finite).
    signals : ndarray (..., samples)
        [m or rad].
    final, band : ndarray (...)
        [m or rad].
    stop_time : float
        [s].
    hold : float or ndarray (...)
        [s].
    interpolate : bool
        Place the instant the signal enters the band for good between the last sample outside
        and the next one, where ``|s - final| - band`` interpolated linearly is zero (False: the
        last sample outside).

    Returns
    -------
    time : ndarray (...)
        Settling time after the stop [s]; NaN where the signal is still outside
        the band less than ``hold`` before the run ends.
    short : ndarray (...)
        How long before the run's end the signal was last outside [s].
    """
    first = int(np.searchsorted(t, stop_time - 1e-12, side="left"))
    after = signals[..., first:]
    outside = np.abs(after - np.asarray(final, float)[..., None]) > np.asarray(band, float)[..., None]
    if not outside.shape[-1]:
        zero = np.zeros(outside.shape[:-1])
        return zero, zero
    index = outside.shape[-1] - 1 - np.argmax(outside[..., ::-1], axis=-1)
    last = t[first:][index]
    never = ~outside.any(axis=-1)
    crossing = last
    if interpolate and outside.shape[-1] > 1:
        after_t = t[first:]
        following = np.minimum(index + 1, after_t.size - 1)
        gap = np.abs(after - np.asarray(final, float)[..., None]) - np.asarray(band, float)[..., None]
        g0 = np.take_along_axis(gap, index[..., None], axis=-1)[..., 0]
        g1 = np.take_along_axis(gap, following[..., None], axis=-1)[..., 0]
        with np.errstate(all="ignore"):
            weight = np.clip(np.where(g0 - g1 > 0, g0 / (g0 - g1), 0.0), 0.0, 1.0)
        crossing = last + (after_t[following] - last) * weight
    short = t[-1] - crossing
    times = np.where(never, 0.0, crossing - stop_time)
    unsettled = ~never & ((last >= t[-1]) | (short < hold))
    return np.where(unsettled, np.nan, times), np.where(never, 0.0, short)


def signal_bands(rule: Band | Settling, peaks: np.ndarray) -> np.ndarray:
    """Band half-widths [m or rad] of the six signals (..., 6) with these own peaks (:meth:`Band.resolve`)."""
    return as_band(rule).resolve(peaks)


def still_signals(rule: Band | Settling, peaks: np.ndarray) -> np.ndarray:
    """Which signals do not move (own peak at numerical noise): settled at 0 whatever the band."""
    return as_band(rule).still(peaks)


def signal_peaks(signals: np.ndarray) -> np.ndarray:
    """max |s| of each row of ``signals`` (0 for no samples)."""
    if not signals.shape[1]:
        return np.zeros(signals.shape[0])
    return np.maximum(signals.max(axis=1), -signals.min(axis=1))


def signal_settling(
    t: np.ndarray,
    signals: np.ndarray,
    final: np.ndarray | None,
    stop_time: float,
    settling: Band | Settling,
    hold: float | np.ndarray,
    peaks: np.ndarray,
    interpolate: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Settling times of the six table signals of one run or stacked runs, as numbers.

    Parameters
    ----------
    t : ndarray (samples,)
        [s]; from the stop on at least.
    signals : ndarray (..., 6, samples)
        [m or rad].
    final : ndarray (..., 6) or None
        Final equilibrium values (None: a carriage never stops; 0 is the target).
    stop_time : float
        [s].
    settling : Band or Settling
        The band (or the scenario's ``[settling]`` rule).
    hold : float or ndarray (...)
        [s], as in :func:`settling_time`.
    peaks : ndarray (..., 6)
        max |signal| over the whole run [m or rad].
    interpolate : bool
        As for :func:`last_outside`.

    Returns
    -------
    time : ndarray (..., 6)
        [s]; NaN where the run cannot show it; 0 for a signal that does not move.
    short : ndarray (..., 6)
        How long before the run's end each signal was last outside its band [s].
    """
    peaks = np.asarray(peaks, dtype=float)
    if _unavailable(t, stop_time):
        times, short = np.full(peaks.shape, np.nan), np.zeros(peaks.shape)
    else:
        target = np.zeros(peaks.shape) if final is None else np.asarray(final, dtype=float)
        bands = np.maximum(signal_bands(settling, peaks), 1e-300)
        times, short = last_outside(
            t, signals, target, stop_time, bands, np.asarray(hold, dtype=float)[..., None], interpolate
        )
    if final is not None:
        times = np.where(still_signals(settling, peaks), 0.0, times)
    return times, short


def settling_metrics(
    t: np.ndarray,
    signals: np.ndarray,
    final: np.ndarray | None,
    stop_time: float,
    settling: Band | Settling,
    hold: float = 0.0,
    peaks: np.ndarray | None = None,
    interpolate: bool = False,
    tail: FreeTail | None = None,
    rest_note: str = "",
) -> dict[str, SettlingResult]:
    """Settling of each of the six table signals, keyed by name (``SIGNALS``).

    ``peaks`` (max |signal| per row), when the caller has them already; ``interpolate`` as for
    :func:`last_outside`; ``tail`` and ``rest_note`` as for :func:`settling_results` (with a tail, ``hold``
    is not waited: the tail decides).
    """
    if peaks is None:
        peaks = signal_peaks(signals)
    times, short = signal_settling(t, signals, final, stop_time, settling, 0.0 if tail else hold, peaks, interpolate)
    return settling_results(times, short, peaks, final is not None, settling, _unavailable(t, stop_time), tail,
                            rest_note)


def settling_results(
    times: np.ndarray,
    short: np.ndarray,
    peaks: np.ndarray,
    stops: bool,
    settling: Band | Settling,
    why: str = "",
    tail: FreeTail | None = None,
    rest_note: str = "",
) -> dict[str, SettlingResult]:
    """Per signal name: the numbers of :func:`signal_settling` (one run) as :class:`SettlingResult`.

    Parameters
    ----------
    times, short, peaks : ndarray (6,)
        As :func:`signal_settling` gives them [s, s, m or rad].
    stops : bool
        The carriages stop.
    settling : Band or Settling
    why : str
        Why the run shows no settling at all ("" when it can).
    tail : FreeTail, optional
        The free motion after the run's end: a time stands only if the signal stays inside its band
        after the end; a signal outside at the end is told when it would enter for good (without a tail:
        ``times`` as given, NaN where the signal was not seen inside long enough).
    rest_note : str
        What keeps the table off its final rest (said of a signal that comes to rest outside its band).
    """
    bands = signal_bands(settling, peaks)
    kept, reasons = judged_times(times, short, peaks, stops, settling, why, tail, rest_note)
    return {name: _result(None if math.isnan(kept[i]) else float(kept[i]), float(peaks[i]), float(bands[i]), reasons[i])
            for i, name in enumerate(SIGNALS)}


def _result(time: float | None, peak: float, band: float, reason: str) -> SettlingResult:
    """A :class:`SettlingResult` of numbers this module made (its arguments' checks, six per run, skipped)."""
    result = SettlingResult.__new__(SettlingResult)
    _RESULT_INIT(result, time, peak, band, reason)
    return result


def judged_times(
    times: np.ndarray,
    short: np.ndarray,
    peaks: np.ndarray,
    stops: bool,
    settling: Band | Settling,
    why: str = "",
    tail: FreeTail | None = None,
    rest_note: str = "",
) -> tuple[np.ndarray, list[str]]:
    """The rule of :func:`settling_results` as numbers: the six settling times [s] (NaN: none; 0 for a
    signal that does not move) and each one's reason ("" when settled normally)."""
    still = still_signals(settling, peaks) if stops else np.zeros(len(SIGNALS), dtype=bool)
    verdict = None if tail is None or why else tail.judge(np.maximum(signal_bands(settling, peaks), 1e-300))
    kept, reasons = np.array(times, dtype=float), [""] * len(SIGNALS)
    for i in range(len(SIGNALS)):
        if still[i]:
            kept[i], reasons[i] = 0.0, "does not move"
        elif verdict is not None and (verdict.leaves[i] or math.isnan(times[i])):
            kept[i], reasons[i] = math.nan, verdict.reason(i, bool(math.isnan(times[i])), rest_note)
        elif math.isnan(times[i]):
            reasons[i] = why or _outside(short[i])
    return kept, reasons


check_public(globals(), ("SettlingResult", "settling_time"))
