"""Prescribed carriage motion profiles q(t) along a carriage's axis.

Every profile is at rest before its start time ``t0`` and, except the sine,
after its stop time. Profiles evaluate position [m], velocity [m/s] and
acceleration [m/s^2] on arrays of times, vectorised.

Accelerations jump at a profile's breakpoints (a trapezoid's corners). An
integrator that must stay accurate across them asks for one-sided values: the
``piece_time`` argument of :meth:`evaluate` selects the polynomial piece by a
time inside the step, while the polynomial is evaluated at ``t``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import CubicSpline

FloatArray = NDArray[np.float64]

__all__ = [
    "PiecewisePolynomialProfile",
    "Profile",
    "SineProfile",
    "samples",
    "scurve",
    "trapezoid",
]


class Profile:
    """Base class: a rest-to-rest (or endless) motion along one axis."""

    #: times [s] where some derivative of q jumps; the integrator restarts there
    breakpoints: tuple[float, ...]
    #: time [s] after which the carriage is at rest for good (inf: never)
    stop_time: float

    def evaluate(
        self, t: ArrayLike, piece_time: ArrayLike | None = None
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Position [m], velocity [m/s] and acceleration [m/s^2] at times ``t`` [s]."""
        raise NotImplementedError

    def position(self, t: float) -> float:
        """Position [m] at one time ``t`` [s]."""
        return float(self.evaluate(np.array([t]))[0][0])

    @property
    def final_position(self) -> float | None:
        """Position [m] once stopped, or None for a profile that never stops."""
        if math.isinf(self.stop_time):
            return None
        return self.position(self.stop_time + 1.0)

    def position_range(self, t_end: float) -> tuple[float, float]:
        """Least and greatest position [m] reached in [0, t_end] s."""
        raise NotImplementedError


@dataclass(frozen=True)
class PiecewisePolynomialProfile(Profile):
    """q(t) as polynomials in local time on consecutive pieces, held outside.

    Parameters
    ----------
    knots : tuple of float
        Piece boundaries [s], increasing, ``len(coefficients) + 1`` of them.
    coefficients : tuple of tuple of float
        Per piece, ascending powers of ``tau = t - knots[i]``: q = sum c_k tau^k.
    kind : str
        The profile type it came from, for messages and plots.
    """

    knots: tuple[float, ...]
    coefficients: tuple[tuple[float, ...], ...]
    kind: str = "piecewise"
    breakpoints: tuple[float, ...] = field(init=False)
    stop_time: float = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "breakpoints", tuple(self.knots))
        object.__setattr__(self, "stop_time", float(self.knots[-1]))

    def _coefficient_array(self) -> FloatArray:
        return np.array(self.coefficients, dtype=float)

    def evaluate(
        self, t: ArrayLike, piece_time: ArrayLike | None = None
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        t = np.asarray(t, dtype=float)
        sel = t if piece_time is None else np.broadcast_to(np.asarray(piece_time, float), t.shape)
        knots = np.asarray(self.knots)
        coef = self._coefficient_array()
        n_pieces = coef.shape[0]
        piece = np.clip(np.searchsorted(knots, sel, side="right") - 1, 0, n_pieces - 1)
        before = sel < knots[0]
        after = sel >= knots[-1]
        tau = np.where(before, 0.0, np.where(after, knots[-1] - knots[piece], t - knots[piece]))
        c = coef[piece]  # (..., degree+1)
        deg = coef.shape[1] - 1
        q = np.zeros_like(t)
        v = np.zeros_like(t)
        a = np.zeros_like(t)
        for k in range(deg, -1, -1):
            q = q * tau + c[..., k]
        for k in range(deg, 0, -1):
            v = v * tau + k * c[..., k]
        for k in range(deg, 1, -1):
            a = a * tau + k * (k - 1) * c[..., k]
        rest = before | after
        v = np.where(rest, 0.0, v)
        a = np.where(rest, 0.0, a)
        return q, v, a

    def position_range(self, t_end: float) -> tuple[float, float]:
        t = np.linspace(0.0, max(t_end, self.knots[-1]), 2001)
        t = np.union1d(t, np.asarray(self.knots))
        q = self.evaluate(t)[0]
        return float(q.min()), float(q.max())


@dataclass(frozen=True)
class SineProfile(Profile):
    """``offset + amplitude sin(omega (t - t0) + phase)`` for t >= t0, held before.

    Parameters
    ----------
    amplitude : float
        [m]
    omega : float
        Angular frequency [rad/s].
    phase : float
        [rad]
    offset : float
        [m]
    t0 : float
        Start time [s].
    """

    amplitude: float
    omega: float
    phase: float = 0.0
    offset: float = 0.0
    t0: float = 0.0
    kind: str = "sine"
    breakpoints: tuple[float, ...] = field(init=False)
    stop_time: float = field(init=False, default=math.inf)

    def __post_init__(self) -> None:
        object.__setattr__(self, "breakpoints", (float(self.t0),))

    def evaluate(
        self, t: ArrayLike, piece_time: ArrayLike | None = None
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        t = np.asarray(t, dtype=float)
        sel = t if piece_time is None else np.broadcast_to(np.asarray(piece_time, float), t.shape)
        moving = sel >= self.t0
        arg = self.omega * (np.where(moving, t, self.t0) - self.t0) + self.phase
        q = self.offset + self.amplitude * np.sin(arg)
        v = np.where(moving, self.amplitude * self.omega * np.cos(arg), 0.0)
        a = np.where(moving, -self.amplitude * self.omega**2 * np.sin(arg), 0.0)
        return q, v, a

    def position_range(self, t_end: float) -> tuple[float, float]:
        t = np.linspace(0.0, t_end, 20001)
        q = self.evaluate(t)[0]
        span = abs(self.amplitude)
        if t_end - self.t0 >= 2 * math.pi / self.omega:
            return self.offset - span, self.offset + span
        return float(q.min()), float(q.max())


def _from_segments(
    start: float, t0: float, durations: list[float], accelerations: list[float], jerks: list[float]
) -> tuple[tuple[float, ...], tuple[tuple[float, ...], ...]]:
    """Integrate segments of given start acceleration and jerk from rest at ``start``."""
    knots = [t0]
    coefficients = []
    q, v = start, 0.0
    for duration, a0, jerk in zip(durations, accelerations, jerks, strict=True):
        if duration <= 0.0:
            continue
        coefficients.append((q, v, a0 / 2.0, jerk / 6.0))
        q = q + v * duration + a0 * duration**2 / 2.0 + jerk * duration**3 / 6.0
        v = v + a0 * duration + jerk * duration**2 / 2.0
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

    Notes
    -----
    When the stroke is too short to reach ``velocity`` the profile is
    triangular with peak speed ``sqrt(2 |stroke| a d / (a + d))``.
    """
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
    return PiecewisePolynomialProfile(knots, coef, kind="trapezoid")


def scurve(
    start: float, stroke: float, velocity: float, acceleration: float, jerk: float, t0: float = 0.0
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
    """
    distance = abs(stroke)
    sign = 1.0 if stroke >= 0 else -1.0

    def accel_phase(v: float) -> tuple[float, float]:
        """(jerk time, whole acceleration-phase time) to reach speed v from rest."""
        if v * jerk <= acceleration**2:
            tj = math.sqrt(v / jerk)
            return tj, 2.0 * tj
        tj = acceleration / jerk
        return tj, v / acceleration + tj

    v = velocity
    tj, ta = accel_phase(v)
    if v * ta > distance:  # cannot reach the cruise speed: find the peak speed
        v_knee = acceleration**2 / jerk
        if v_knee * 2.0 * math.sqrt(v_knee / jerk) >= distance:
            v = (distance * math.sqrt(jerk) / 2.0) ** (2.0 / 3.0)
        else:
            r = acceleration / jerk
            v = acceleration / 2.0 * (-r + math.sqrt(r * r + 4.0 * distance / acceleration))
        tj, ta = accel_phase(v)
    a_peak = jerk * tj
    t_const = max(ta - 2.0 * tj, 0.0)
    t_cruise = max(distance - v * ta, 0.0) / v if v > 0 else 0.0
    s = sign
    durations = [tj, t_const, tj, t_cruise, tj, t_const, tj]
    accels = [0.0, s * a_peak, s * a_peak, 0.0, 0.0, -s * a_peak, -s * a_peak]
    jerks = [s * jerk, 0.0, -s * jerk, 0.0, -s * jerk, 0.0, s * jerk]
    knots, coef = _from_segments(start, t0, durations, accels, jerks)
    return PiecewisePolynomialProfile(knots, coef, kind="scurve")


def samples(t: ArrayLike, q: ArrayLike) -> PiecewisePolynomialProfile:
    """Clamped cubic spline through samples, zero velocity at both ends.

    Parameters
    ----------
    t : array_like
        Sample times [s], strictly increasing, at least two.
    q : array_like
        Positions [m] at those times.
    """
    t = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    spline = CubicSpline(t, q, bc_type="clamped")
    coef = spline.c[::-1].T  # ascending powers per piece
    return PiecewisePolynomialProfile(
        tuple(float(x) for x in t), tuple(tuple(float(c) for c in row) for row in coef), kind="samples"
    )
