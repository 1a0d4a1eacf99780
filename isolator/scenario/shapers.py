"""Input shapers: trains of impulses that cancel the residual vibration of a mode when a move is convolved
with them (ZV, ZVD; EI from Singhose et al., "Vibration reduction using multi-hump input shapers", 1997: the
damped extra-insensitive shaper's curve-fitted amplitudes and times).

Pure formulas of a mode's frequency and damping: scenario files can give a step's shaper
(``[sequence]``), and :mod:`controllers.profiles.input_shaping` tunes them to the table's modes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public

__all__ = ["EI_TOLERANCE", "SHAPERS", "Shaper", "convolved", "residual_vibration", "shaper"]

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

    Returns
    -------
    Shaper
        The impulse amplitudes (summing to 1) and times [s].

    Examples
    --------
    The ZV shaper of an undamped mode: two halves, half a period apart.

    >>> from controllers.profiles import shaper
    >>> zv = shaper("zv", 2.0, 0.0)
    >>> [round(a, 6) for a in zv.amplitudes], [round(t, 6) for t in zv.times]
    ([0.5, 0.5], [0.0, 0.25])
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

    Parameters
    ----------
    train : Shaper
        The impulse train (amplitudes, times [s]).
    frequency : float
        The mode's undamped natural frequency [Hz].
    damping : float
        The mode's damping ratio [-].

    Returns
    -------
    float
        The residual amplitude relative to one unit impulse [-]: 0 for a ZV shaper at its own mode.

    Examples
    --------
    >>> from controllers.profiles import residual_vibration, shaper
    >>> zv = shaper("zv", 3.4, 0.05)
    >>> round(residual_vibration(zv, 3.4, 0.05), 12)
    0.0
    >>> undamped = shaper("zv", 3.4, 0.0)       # 20 % off the mode: |cos(pi 1.2 / 2)| = 0.309
    >>> round(residual_vibration(undamped, 3.4 * 1.2, 0.0), 3)
    0.309
    """
    w = 2 * math.pi * frequency
    wd = w * math.sqrt(1 - damping**2)
    t = np.asarray(train.times)
    a = np.asarray(train.amplitudes)
    total = np.sum(a * np.exp(damping * w * t) * np.exp(1j * wd * t))
    return float(np.exp(-damping * w * t[-1]) * abs(total))


def convolved(trains: Sequence[Shaper]) -> tuple[list[float], list[float]]:
    """The impulse train of shapers applied one after the other (one per mode): every combination of their
    impulses, amplitudes multiplied [-] and times added [s]; ``([1], [0])`` for none."""
    amplitudes, times = np.ones(1), np.zeros(1)
    for train in trains:
        amplitudes = np.outer(amplitudes, train.amplitudes).ravel()
        times = np.add.outer(times, train.times).ravel()
    return [float(a) for a in amplitudes], [float(t) for t in times]


check_public(globals(), ("Shaper", "residual_vibration"))
