"""Building motion profiles: trapezoid, seven-segment S-curve, shaped and sampled moves.

Each builder returns a :class:`~isolator.scenario.profiles.PiecewisePolynomialProfile` made of cubic pieces
(constant jerk per piece), at rest before ``t0`` and after the stop.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public
from isolator.scenario.profiles import PiecewisePolynomialProfile
from isolator.scenario.rules import check_arguments

__all__ = ["samples", "scurve", "segment_starts", "segments", "shaped", "trapezoid"]


def segments(
    start: float,
    t0: float,
    durations: Sequence[float],
    accelerations: Sequence[float],
    jerks: Sequence[float],
    kind: str = "segments",
) -> PiecewisePolynomialProfile:
    """A move from rest at ``start`` through segments of constant jerk.

    Parameters
    ----------
    start : float
        Position at rest before ``t0`` [m].
    t0 : float
        Start time [s].
    durations : sequence of float
        Segment lengths [s]; empty (zero) segments are skipped.
    accelerations : sequence of float
        Acceleration at each segment's start [m/s^2].
    jerks : sequence of float
        Constant jerk within each segment [m/s^3].
    kind : str
        The name the profile reports.

    Returns
    -------
    PiecewisePolynomialProfile
        The move: cubic pieces, at rest before ``t0`` and after the last segment.
    """
    check_arguments(start=start, t0=t0)
    given = {name: _numbers(value, name) for name, value in
             (("durations", durations), ("accelerations", accelerations), ("jerks", jerks))}
    n = given["durations"].size
    for name, values in given.items():
        if values.size != n:
            raise ParameterError(f"{name}: {values.size} values for {n} durations (one per segment)")
    if np.any(given["durations"] < 0):
        raise ParameterError(f"durations: must be >= 0 [s], got {given['durations'].min():g}")
    knots, coef = _from_segments(start, t0, *(tuple(map(float, v)) for v in given.values()))
    return PiecewisePolynomialProfile(knots, coef, kind=kind)


def _numbers(value: object, name: str) -> np.ndarray:
    """A 1-D array of finite numbers, or a ParameterError naming ``name``."""
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}: must be a sequence of numbers, got {type(value).__name__}") from None
    if out.ndim != 1 or not np.all(np.isfinite(out)):
        raise ParameterError(f"{name}: must be a sequence of finite numbers (1-D), got shape {out.shape}")
    return out


def segment_starts(
    start: Any, durations: Sequence[Any], accelerations: Sequence[Any], jerks: Sequence[Any]
) -> list[tuple[Any, Any]]:
    """Position [m] and speed [m/s] at the start of each constant-jerk segment, then at the end.

    From rest at ``start``; plain arithmetic, so the quantities may be numbers
    or casadi expressions (the profile optimiser's).
    """
    q, v = start, 0.0
    out = [(q, v)]
    for duration, a0, jerk in zip(durations, accelerations, jerks, strict=True):
        q = q + v * duration + a0 * duration**2 / 2.0 + jerk * duration**3 / 6.0
        v = v + a0 * duration + jerk * duration**2 / 2.0
        out.append((q, v))
    return out


def _from_segments(
    start: float, t0: float, durations: Sequence[float], accelerations: Sequence[float], jerks: Sequence[float]
) -> tuple[tuple[float, ...], tuple[tuple[float, ...], ...]]:
    """Integrate segments of given start acceleration and jerk from rest at ``start``."""
    knots = [t0]
    coefficients = []
    states = segment_starts(start, durations, accelerations, jerks)
    for (q, v), duration, a0, jerk in zip(states, durations, accelerations, jerks, strict=False):
        if duration <= 0.0:
            continue
        coefficients.append((q, v, a0 / 2.0, jerk / 6.0))
        knots.append(knots[-1] + duration)
    if not coefficients:  # no motion at all: one empty piece holding the start
        coefficients.append((start, 0.0, 0.0, 0.0))
        knots.append(t0)
    return tuple(knots), tuple(coefficients)


def trapezoid(
    start: float,
    stroke: float,
    velocity: float,
    acceleration: float,
    t0: float = 0.0,
    deceleration: float | None = None,
) -> PiecewisePolynomialProfile:
    """Rest-to-rest move with a trapezoidal (or triangular) speed.

    Parameters
    ----------
    start : float
        Position at rest before ``t0`` [m].
    stroke : float
        Signed travel [m].
    velocity : float
        Cruise speed limit [m/s], > 0.
    acceleration, deceleration : float
        [m/s^2], > 0; ``deceleration`` defaults to ``acceleration``.
    t0 : float
        Start time [s].

    Returns
    -------
    PiecewisePolynomialProfile
        The move: accelerating, cruising (if the speed is reached) and braking at constant acceleration.

    Notes
    -----
    When the stroke is too short to reach ``velocity`` the profile is
    triangular with peak speed ``sqrt(2 |stroke| a d / (a + d))``.

    Examples
    --------
    A stroke too short for the speed limit: a triangle, peak speed ``sqrt(2 |stroke| a d / (a + d))``

    >>> from isolator import trapezoid
    >>> move = trapezoid(start=0.0, stroke=0.1, velocity=1.0, acceleration=2.0)
    >>> round(move.stop_time, 4), round(2 * (0.1 / 2.0) ** 0.5, 4)   # [s]: two halves of sqrt(s / a)
    (0.4472, 0.4472)
    """
    check_arguments(start=start, stroke=stroke, velocity=velocity, acceleration=acceleration, t0=t0,
                    **({} if deceleration is None else {"deceleration": deceleration}))
    dec = acceleration if deceleration is None else deceleration
    distance = abs(stroke)
    sign = 1.0 if stroke >= 0 else -1.0
    peak = min(velocity, math.sqrt(2.0 * distance * acceleration * dec / (acceleration + dec)))
    t_acc = peak / acceleration
    t_dec = peak / dec
    cruise = distance - peak * (t_acc + t_dec) / 2.0
    t_cruise = max(cruise, 0.0) / peak if peak > 0 else 0.0
    knots, coef = _from_segments(
        start,
        t0,
        [t_acc, t_cruise, t_dec],
        [sign * acceleration, 0.0, -sign * dec],
        [0.0, 0.0, 0.0],
    )
    spec = {"start": start, "stroke": stroke, "velocity": velocity, "acceleration": acceleration, "t0": t0}
    if deceleration is not None:
        spec["deceleration"] = deceleration
    return PiecewisePolynomialProfile(knots, coef, kind="trapezoid", spec=_spec(spec))


def _spec(values: dict[str, float]) -> tuple[tuple[str, float], ...]:
    return tuple((k, float(v)) for k, v in values.items())


def scurve(
    start: float,
    stroke: float,
    velocity: float,
    acceleration: float,
    jerk: float,
    t0: float = 0.0,
    deceleration: float | None = None,
    deceleration_jerk: float | None = None,
) -> PiecewisePolynomialProfile:
    """Jerk-limited seven-segment rest-to-rest move.

    Parameters
    ----------
    start : float
        Position at rest before ``t0`` [m].
    stroke : float
        Signed travel [m].
    velocity, acceleration, jerk : float
        Limits [m/s], [m/s^2], [m/s^3], all > 0. When the stroke is too short
        the cruise speed (and if need be the peak acceleration) is lowered so
        that the move stays jerk-limited and rest-to-rest.
    t0 : float
        Start time [s].
    deceleration : float, optional
        Limit of the braking phase [m/s^2]; defaults to ``acceleration``.
    deceleration_jerk : float, optional
        Jerk of the braking phase [m/s^3]; defaults to ``jerk``.

    Returns
    -------
    PiecewisePolynomialProfile
        The move: seven segments of constant jerk (fewer when a limit is not reached).

    Examples
    --------
    >>> from isolator import scurve
    >>> move = scurve(start=-0.4, stroke=0.8, velocity=0.4, acceleration=1.0, jerk=20.0)
    >>> round(move.stop_time, 3), move.position(move.stop_time)
    (2.45, 0.4)
    """
    optional = {k: v for k, v in (("deceleration", deceleration), ("deceleration_jerk", deceleration_jerk))
                if v is not None}
    check_arguments(start=start, stroke=stroke, velocity=velocity, acceleration=acceleration, jerk=jerk, t0=t0,
                    **optional)
    dec = acceleration if deceleration is None else deceleration
    jerk_down = jerk if deceleration_jerk is None else deceleration_jerk
    distance = abs(stroke)
    s = 1.0 if stroke >= 0 else -1.0

    def phase(v: float, a: float, j: float) -> tuple[float, float]:
        """(jerk time, whole phase time) to change speed by v with limits a and j."""
        if v * j <= a * a:
            tj = math.sqrt(v / j)
            return tj, 2.0 * tj
        return a / j, v / a + a / j

    def travel(v: float) -> float:
        """Distance of the accelerating and braking phases at peak speed v."""
        return v * (phase(v, acceleration, jerk)[1] + phase(v, dec, jerk_down)[1]) / 2.0

    v = velocity
    if travel(v) > distance:  # cannot reach the cruise speed: the peak speed that covers the stroke
        v = brentq(lambda u: travel(u) - distance, 0.0, velocity, xtol=1e-15, rtol=4.0 * np.finfo(float).eps)
    tja, ta = phase(v, acceleration, jerk)
    tjd, td = phase(v, dec, jerk_down)
    t_cruise = max(distance - travel(v), 0.0) / v if v > 0 else 0.0
    a_up, a_down = jerk * tja, jerk_down * tjd
    durations = [tja, ta - 2.0 * tja, tja, t_cruise, tjd, td - 2.0 * tjd, tjd]
    accels = [0.0, s * a_up, s * a_up, 0.0, 0.0, -s * a_down, -s * a_down]
    jerks = [s * jerk, 0.0, -s * jerk, 0.0, -s * jerk_down, 0.0, s * jerk_down]
    knots, coef = _from_segments(start, t0, [max(d, 0.0) for d in durations], accels, jerks)
    spec = {"start": start, "stroke": stroke, "velocity": velocity, "acceleration": acceleration,
            "jerk": jerk, "t0": t0}
    if deceleration is not None:
        spec["deceleration"] = deceleration
    if deceleration_jerk is not None:
        spec["deceleration_jerk"] = deceleration_jerk
    return PiecewisePolynomialProfile(knots, coef, kind="scurve", spec=_spec(spec))


def shaped(profile: PiecewisePolynomialProfile, amplitudes: Sequence[float], delays: Sequence[float],
           kind: str = "shaped") -> PiecewisePolynomialProfile:
    """A profile convolved with an impulse sequence (input shaping).

    ``q_shaped(t) = sum_i A_i q(t - t_i)`` with ``sum A_i = 1``, so the shaped
    move has the same start and stroke, ends ``max(t_i)`` later, and keeps
    within the speed and acceleration limits when every ``A_i >= 0``.

    Parameters
    ----------
    profile : PiecewisePolynomialProfile
        A rest-to-rest move (cubic pieces at most).
    amplitudes : sequence of float
        Impulse amplitudes, summing to 1.
    delays : sequence of float
        Impulse times [s], >= 0.
    kind : str
        The name the shaped profile reports.

    Returns
    -------
    PiecewisePolynomialProfile
        The shaped move, ``max(delays)`` longer than ``profile``.
    """
    amps, lags = _numbers(amplitudes, "amplitudes"), _numbers(delays, "delays")
    if amps.shape != lags.shape or amps.size == 0:
        raise ParameterError(f"amplitudes, delays: need one delay per amplitude, got {amps.size} amplitudes and "
                             f"{lags.size} delays")
    if abs(amps.sum() - 1.0) > 1e-9 or np.any(lags < 0):
        raise ParameterError("amplitudes: must sum to 1, with delays >= 0")
    if not isinstance(profile, PiecewisePolynomialProfile):
        raise ParameterError(f"profile: must be a PiecewisePolynomialProfile, got {type(profile).__name__}")
    if profile._coefficient_array().shape[1] > 4:
        raise ParameterError("profile: shaping takes pieces of degree 3 at most")
    base = np.asarray(profile.knots)
    knots = np.unique(np.concatenate([base + d for d in lags]))
    lo, hi = knots[:-1], knots[1:]
    mid = (lo + hi) / 2.0
    total = [np.zeros(lo.size) for _ in range(3)]
    a_end = np.zeros(lo.size)
    for amp, lag in zip(amps, lags, strict=True):
        q, v, a = profile.evaluate(lo - lag, mid - lag)
        for k, value in enumerate((q, v, a)):
            total[k] += amp * value
        a_end += amp * profile.evaluate(hi - lag, mid - lag)[2]
    jerk = (a_end - total[2]) / (hi - lo)
    coef = np.column_stack([total[0], total[1], total[2] / 2.0, jerk / 6.0])
    return PiecewisePolynomialProfile(
        tuple(float(k) for k in knots), tuple(tuple(float(c) for c in row) for row in coef), kind=kind
    )


def samples(t: ArrayLike, q: ArrayLike) -> PiecewisePolynomialProfile:
    """Clamped cubic spline through samples, zero velocity at both ends.

    Parameters
    ----------
    t : array_like
        Sample times [s], strictly increasing, at least two.
    q : array_like
        Positions [m] at those times.

    Returns
    -------
    PiecewisePolynomialProfile
        The spline as a profile (position, velocity, acceleration, jerk at any time).
    """
    try:
        t = np.asarray(t, dtype=float).ravel()
        q = np.asarray(q, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ParameterError("t, q: must be sequences of numbers") from None
    if t.size < 2 or q.size != t.size:
        raise ParameterError(f"q: needs one position per sample time, two or more ({t.size} times, {q.size} q)")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q))):
        raise ParameterError("t, q: samples must be finite (found NaN or infinity)")
    if np.any(np.diff(t) <= 0):
        raise ParameterError("t: sample times must be strictly increasing")
    if t[0] < 0:
        raise ParameterError(f"t: sample times must be >= 0, got {t[0]:g}")
    spline = CubicSpline(t, q, bc_type="clamped")
    coef = spline.c[::-1].T  # ascending powers per piece
    return PiecewisePolynomialProfile(
        tuple(float(x) for x in t), tuple(tuple(float(c) for c in row) for row in coef), kind="samples"
    )


check_public(globals(), ("samples", "scurve", "segments", "shaped", "trapezoid"))
