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

from isolator.scenario.arguments import check_public

FloatArray = NDArray[np.float64]

__all__ = ["FloatArray", "PiecewisePolynomialProfile", "Profile", "SineProfile"]


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
    spec : tuple of (str, float) pairs
        The keys of the scenario file's profile table that build it again
        (``type`` aside), when it came from a trapezoid or an S-curve; empty
        otherwise. See :attr:`settings`.
    """

    knots: tuple[float, ...]
    coefficients: tuple[tuple[float, ...], ...]
    kind: str = "piecewise"
    spec: tuple[tuple[str, float], ...] = field(default=(), compare=False)
    breakpoints: tuple[float, ...] = field(init=False)
    stop_time: float = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "breakpoints", tuple(self.knots))
        object.__setattr__(self, "stop_time", float(self.knots[-1]))

    @property
    def settings(self) -> dict[str, float | str]:
        """The profile as a scenario file's profile table (``type`` and its keys).

        Raises
        ------
        ValueError
            The profile was not built from a trapezoid's or an S-curve's keys.
        """
        if not self.spec:
            raise ValueError(f"a '{self.kind}' profile has no trapezoid or scurve keys to write")
        return {"type": self.kind, **dict(self.spec)}

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
    kind : str
        The profile's type name, ``sine``.
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


check_public(globals(), ("PiecewisePolynomialProfile", "SineProfile"))
