"""Numbers as people read them: times computed from a scenario's inputs without the arithmetic's dust,
values at rounding level of their signal's scale as zero, lengths in a unit that suits them."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["DUST", "clean_time", "length_text", "number_text", "without_dust"]

#: relative size below which a value is rounding dust (of its own size for times, of its signal's scale else)
DUST = 1e-12

_LENGTH_UNITS = ((1e-6, 1e9, "nm"), (1e-3, 1e6, "µm"), (1.0, 1e3, "mm"))


def clean_time(t: float) -> float:
    """A time computed from input times [s], rounded to 12 significant digits (``7.8999999999999995`` ->
    ``7.9``): the inputs' own value where the arithmetic added dust; infinities and NaN as they are."""
    t = float(t)
    if not math.isfinite(t) or t == 0.0:
        return t
    return float(f"{t:.12g}")


def without_dust(values: np.ndarray | float, scale: np.ndarray | float) -> np.ndarray:
    """``values`` with those at most :data:`DUST` times their ``scale`` (broadcast) set to 0."""
    values = np.asarray(values, dtype=float)
    return np.where(np.abs(values) <= DUST * np.abs(np.asarray(scale, dtype=float)), 0.0, values)


def length_text(meters: float, digits: int = 4) -> str:
    """A length [m] in nm, µm, mm or m, whichever keeps the number between 1 and 1000 (``1 m``, not
    ``1e+09 nm``)."""
    size = abs(float(meters))
    for below, factor, unit in _LENGTH_UNITS:
        if size < below:
            return f"{meters * factor:.{digits}g} {unit}"
    return f"{meters:.{digits}g} m"


def number_text(value: float, digits: int = 3) -> str:
    """``value`` to ``digits`` significant digits without an exponent where one is not needed (``2624``, not
    ``2.62e+03``; ``13.2``; ``0.0293``): every digit of the integer part kept, plain notation from 1e-3 to 1e6,
    ``:.{digits}g`` outside it (``1.5e+07``); ``0`` for zero, ``inf`` and ``nan`` as they are.

    Examples
    --------
    >>> number_text(2624.3), number_text(13.24), number_text(9.996), number_text(1.5e7)
    ('2624', '13.2', '10.0', '1.5e+07')
    """
    value = float(value)
    if value == 0.0 or not math.isfinite(value):
        return f"{value:g}"
    size = abs(value)
    if not 1e-3 <= size < 1e6:
        return f"{value:.{digits}g}"
    rounded = abs(float(f"{value:.{digits}g}"))  # 9.996 -> 10.0: its digits counted after rounding
    decimals = max(digits - 1 - math.floor(math.log10(rounded)), 0)
    return f"{value:.{decimals}f}"
