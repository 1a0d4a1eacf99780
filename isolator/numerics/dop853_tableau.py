"""The DOP853 tableau: Dormand and Prince's 8(5,3) method with its 7th-order continuous extension.

The coefficients are data (``data/dop853.toml``), transcribed from Hairer and
Wanner's Fortran code ``dop853.f`` under the code's names (``a1514``,
``d411``, ...). :func:`dop853_tableau` turns them into the arrays the steppers
use, with the dense output rewritten in powers of the step fraction.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numpy as np
from numpy.polynomial import polynomial as poly

__all__ = ["STAGES", "Tableau", "dop853_coefficients", "dop853_tableau"]

#: right-hand-side evaluations per step (twelve, the end point, three for the dense output)
STAGES = 16
#: the stage evaluated at the new state (0-based; its row of ``a`` holds the weights ``b``)
END = 12
#: the dense output's polynomial degree in the step fraction
DEGREE = 7


@dataclass(frozen=True)
class Tableau:
    """An explicit Runge-Kutta method whose stage ``end`` is the step's new state.

    Attributes
    ----------
    a : ndarray (stages, stages)
        Strictly lower-triangular stage coefficients.
    c : ndarray (stages,)
        Stage times as fractions of the step.
    end : int
        The stage evaluated at the new state (its row of ``a`` holds the weights).
    dense : ndarray (stages, degree)
        ``y(t0 + s h) = y0 + h sum_i K_i sum_j dense[i, j] s^(j+1)`` for ``0 <= s <= 1``.
    """

    a: np.ndarray
    c: np.ndarray
    end: int
    dense: np.ndarray

    @property
    def weights(self) -> np.ndarray:
        return self.a[self.end, : self.end]


def _stage(name: str, letter: str) -> int:
    """``("c14", "c") -> 13``: the 0-based stage of a one-index coefficient name."""
    if re.fullmatch(rf"{letter}[1-9][0-9]?", name) is None or not 1 <= int(name[1:]) <= STAGES:
        raise ValueError(f"dop853.toml: cannot read the coefficient name {name!r}")
    return int(name[1:]) - 1


def _indices(name: str, rows: range) -> tuple[int, int]:
    """``("a1514", ...) -> (15, 14)``: Hairer's row and stage numbers (1-based) of a coefficient name,
    the one split of its digits with a row in ``rows`` and a stage below 17 (and below the row for ``a``)."""
    digits = name[1:]
    splits = [
        (int(digits[:k]), int(digits[k:]))
        for k in range(1, len(digits))
        if digits[k] != "0" and int(digits[:k]) in rows and 1 <= int(digits[k:]) <= STAGES
    ]
    if name[0] == "a":
        splits = [(i, j) for i, j in splits if j < i]
    if len(splits) != 1:
        raise ValueError(f"dop853.toml: cannot read the coefficient name {name!r}")
    return splits[0]


@lru_cache(maxsize=1)
def dop853_coefficients() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The transcribed coefficients as arrays (0-based stages).

    Returns
    -------
    a : ndarray (16, 16)
        Stage coefficients, the weights ``b`` in row 12 (stage 13, the new state).
    c : ndarray (16,)
        Stage times as fractions of the step.
    d : ndarray (4, 16)
        The dense output's coefficient rows 4-7 (Hairer's ``d4j`` .. ``d7j``).
    """
    text = resources.files("isolator.numerics").joinpath("data", "dop853.toml").read_text()
    data = tomllib.loads(text)
    a, c, d = np.zeros((STAGES, STAGES)), np.zeros(STAGES), np.zeros((DEGREE - 3, STAGES))
    for name, value in data["c"].items():
        c[_stage(name, "c")] = value
    for name, value in data["b"].items():
        a[END, _stage(name, "b")] = value
    for name, value in data["a"].items():
        i, j = _indices(name, range(2, STAGES + 1))
        a[i - 1, j - 1] = value
    for name, value in data["d"].items():
        i, j = _indices(name, range(4, DEGREE + 1))
        d[i - 4, j - 1] = value
    return a, c, d


@lru_cache(maxsize=1)
def dop853_tableau() -> Tableau:
    """Dormand and Prince's 8(5,3) method with its 7th-order continuous extension, 16 stages.

    Returns
    -------
    Tableau
        Stage 12 is the right-hand side at the new state; stages 13-15 serve
        the dense output only.
    """
    a, c, d = dop853_coefficients()
    end = END
    # Hairer's form: y = y0 + x (F0 + (1-x) (F1 + x (F2 + (1-x) (F3 + x (F4 + (1-x) (F5 + x F6))))))
    # with F0 = dy, F1 = h K0 - dy, F2 = 2 dy - h (K_end + K0), F3.. = h D K, dy = h sum b K
    # (the code's CONT(J + NRD * k), k = 1..7).
    n_f = DEGREE
    f_of_k = np.zeros((n_f, STAGES))  # F_j = h * f_of_k[j] @ K
    dy = np.zeros(STAGES)
    dy[:end] = a[end, :end]
    f_of_k[0] = dy
    f_of_k[1] = -dy
    f_of_k[1, 0] += 1.0
    f_of_k[2] = 2 * dy
    f_of_k[2, [0, end]] -= 1.0
    f_of_k[3:] = d
    x, one_minus_x = np.array([0.0, 1.0]), np.array([1.0, -1.0])
    basis = []
    factor = np.array([1.0])
    for j in range(n_f):  # the polynomial multiplying F_j: x, x(1-x), x^2(1-x), x^2(1-x)^2, ...
        factor = poly.polymul(factor, x if j % 2 == 0 else one_minus_x)
        basis.append(factor)
    powers = np.zeros((n_f, n_f))  # powers[j, k]: coefficient of x^(k+1) in basis j
    for j, b in enumerate(basis):
        powers[j, : b.size - 1] = b[1:]
    return Tableau(a, c, end, f_of_k.T @ powers)
