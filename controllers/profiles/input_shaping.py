"""Input shapers (ZV, ZVD, EI) on the carriages' moves, tuned to the modes each move excites.

A shaper is a short train of impulses ``(A_i, t_i)``; convolving a move with it
cancels the residual vibration of one mode (ZV), also its first derivative in
frequency (ZVD), or keeps it below 5 % over a wide band (EI, Singhose et al.,
"Vibration reduction using multi-hump input shapers", 1997: the damped
extra-insensitive shaper's curve-fitted amplitudes and times). Each carriage
is shaped for the mode its move excites most in the table's settling signals
(:func:`dominant_modes`), at the configuration where the move ends.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from controllers.feedforward.wrench import carriage_inertia_wrench
from isolator.analysis.linear import linearise
from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.definitions import Scenario
from isolator.scenario.profile_shapes import shaped
from isolator.scenario.profiles import PiecewisePolynomialProfile

from .move_metrics import with_moves

__all__ = [
    "SHAPERS",
    "ExcitedMode",
    "Shaper",
    "dominant_modes",
    "residual_vibration",
    "shaped_scenario",
    "shaper",
]

SHAPERS = ("zv", "zvd", "ei")

#: the extra-insensitive shaper's vibration tolerance at the design frequency
EI_TOLERANCE = 0.05


@dataclass(frozen=True)
class Shaper:
    """An impulse train.

    Attributes
    ----------
    kind : str
    amplitudes : tuple of float
        Summing to 1.
    times : tuple of float
        [s], the first 0.
    frequency : float
        Design frequency [Hz] (undamped).
    damping : float
        Design damping ratio.
    """

    kind: str
    amplitudes: tuple[float, ...]
    times: tuple[float, ...]
    frequency: float
    damping: float

    @property
    def duration(self) -> float:
        """How much longer a shaped move takes [s]."""
        return self.times[-1]


def shaper(kind: str, frequency: float, damping: float) -> Shaper:
    """The ZV, ZVD or EI shaper of a mode.

    Parameters
    ----------
    kind : {"zv", "zvd", "ei"}
    frequency : float
        Undamped natural frequency [Hz], > 0.
    damping : float
        Damping ratio, in [0, 1).
    """
    if kind not in SHAPERS:
        raise ParameterError(f"kind: must be one of {', '.join(SHAPERS)}, got '{kind}'")
    if not (math.isfinite(frequency) and frequency > 0):
        raise ParameterError(f"frequency: must be a finite number > 0, got {frequency}")
    if not (math.isfinite(damping) and 0 <= damping < 1):
        raise ParameterError(f"damping: must be in [0, 1), got {damping}")
    root = math.sqrt(1 - damping**2)
    period = 1.0 / (frequency * root)  # damped period
    k = math.exp(-damping * math.pi / root)
    if kind == "zv":
        amps, times = [1.0, k], [0.0, period / 2]
    elif kind == "zvd":
        amps, times = [1.0, 2 * k, k * k], [0.0, period / 2, period]
    else:
        v, z = EI_TOLERANCE, damping
        a1 = (0.24968 + 0.24961 * v) + ((0.80008 + 1.23328 * v) + (0.49599 + 3.17316 * v) * z) * z
        a3 = (0.25149 + 0.21474 * v) + ((-0.83249 + 1.41498 * v) + (0.85181 - 4.90094 * v) * z) * z
        t2 = 0.4999 + (((0.46159 + 8.57843 * v) * v)
                       + (((4.26169 - 108.644 * v) * v) + ((1.75601 + 336.989 * v) * v) * z) * z) * z
        amps, times = [a1, 1 - a1 - a3, a3], [0.0, t2 * period, period]
    total = sum(amps)
    return Shaper(kind, tuple(a / total for a in amps), tuple(times), frequency, damping)


def residual_vibration(train: Shaper, frequency: float, damping: float) -> float:
    """Vibration left by the impulse train in a mode, relative to a single unit impulse at its last time.

    ``exp(-zeta w t_N) |sum A_i exp(zeta w t_i) exp(j w_d t_i)|`` (Singer and Seering, 1990; the
    convention the EI shaper's 5 % refers to).
    """
    w = 2 * math.pi * frequency
    wd = w * math.sqrt(1 - damping**2)
    t = np.asarray(train.times)
    a = np.asarray(train.amplitudes)
    total = np.sum(a * np.exp(damping * w * t) * np.exp(1j * wd * t))
    return float(np.exp(-damping * w * t[-1]) * abs(total))


@dataclass(frozen=True)
class ExcitedMode:
    """A mode of the table and how much one carriage's move excites it.

    Attributes
    ----------
    frequency : float
        Undamped natural frequency [Hz].
    damping : float
        Damping ratio.
    weight : float
        Largest step response of the six signals to the carriage's
        acceleration, each over its peak in the reference run [1 / (m/s^2)].
    """

    frequency: float
    damping: float
    weight: float


def dominant_modes(scenario: Scenario, carriage: int, peaks: Sequence[float] | None = None) -> list[ExcitedMode]:
    """The table's modes ranked by how much the carriage's acceleration excites them where the move ends.

    Parameters
    ----------
    scenario : Scenario
    carriage : int
        Index of the carriage.
    peaks : sequence of float, optional
        Each signal's scale [m, rad] (e.g. its peak in the baseline run, which
        sets its settling band); default 1 for all.

    Notes
    -----
    Accelerating carriage ``c`` along its axis ``e`` (world axes) at ``a``
    pushes the table with ``-a m e`` at every mass ``m`` that rides along (the
    carriage and the ones it carries): a wrench at the table's mass centre.
    For each mode ``i`` of the linearised table, the step response of signal
    ``s`` to that wrench has the amplitude ``|C_s v_i w_i' B u| / |lambda_i|``.
    """
    finals = scenario.final_positions()
    if finals is None:
        raise ScenarioError("carriages: a move that never stops has no residual vibration to shape")
    lin = linearise(scenario, positions=finals)
    sys = lin.system
    a, b, c = np.asarray(sys.A), np.asarray(sys.B), np.asarray(sys.C)[:6]
    wrench_cols = [list(sys.input_labels).index(n) for n in ("force:x", "force:y", "force:z",
                                                            "torque:x", "torque:y", "torque:z")]
    unit = np.zeros((finals.size, 1))
    unit[carriage] = 1.0
    u = -carriage_inertia_wrench(scenario, finals[:, None], unit)[0]  # the push on the table
    scale = np.ones(6) if peaks is None else np.maximum(np.asarray(peaks, dtype=float), 1e-300)
    lam, v = np.linalg.eig(a)
    w = np.linalg.inv(v)
    excitation = w @ (b[:, wrench_cols] @ u)
    modes = []
    for i in np.flatnonzero(lam.imag > 1e-9):
        response = np.abs(c @ v[:, i] * excitation[i]) / abs(lam[i]) * 2  # the pair's two halves
        omega = abs(lam[i])
        modes.append(ExcitedMode(omega / (2 * math.pi), -lam[i].real / omega, float(np.max(response / scale))))
    return sorted(modes, key=lambda m: -m.weight)


def shaped_scenario(scenario: Scenario, kind: str, peaks: Sequence[float] | None = None, modes: int = 1) -> Scenario:
    """The scenario with every carriage's move convolved with a shaper.

    Parameters
    ----------
    scenario : Scenario
    kind : {"zv", "zvd", "ei"}
    peaks : sequence of float, optional
        Signal scales for ranking the modes (see :func:`dominant_modes`).
    modes : int
        Shape for this many of each carriage's most excited modes (the
        shapers convolved; each adds its own duration).
    """
    profiles = []
    for i, carriage in enumerate(scenario.carriages):
        profile = carriage.profile
        if not isinstance(profile, PiecewisePolynomialProfile) or math.isinf(profile.stop_time):
            raise ScenarioError(f"carriages[{i}].profile: input shaping needs a rest-to-rest move")
        amps, times = np.array([1.0]), np.array([0.0])
        for mode in dominant_modes(scenario, i, peaks)[:modes]:
            train = shaper(kind, mode.frequency, mode.damping)
            amps = np.outer(amps, train.amplitudes).ravel()
            times = np.add.outer(times, train.times).ravel()
        profiles.append(shaped(profile, list(amps), list(times), kind=f"{kind}-shaped"))
    return with_moves(scenario, profiles)


