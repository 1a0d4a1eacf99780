"""The DOP853 tableau transcribed from Hairer's dop853.f (isolator/numerics/data/dop853.toml) against
SciPy's copy of the same coefficients (a private SciPy module: compared here only, never imported by
the package), and the form the steppers use against Hairer's dense output as the code evaluates it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from isolator.numerics.dop853_tableau import DEGREE, END, STAGES, _indices, dop853_coefficients, dop853_tableau


def test_the_transcribed_coefficients_are_scipys():
    scipy_coefficients = pytest.importorskip("scipy.integrate._ivp.dop853_coefficients")
    a, c, d = dop853_coefficients()
    assert (STAGES, END, DEGREE) == (
        scipy_coefficients.N_STAGES_EXTENDED, scipy_coefficients.N_STAGES, scipy_coefficients.INTERPOLATOR_POWER
    )
    # both parse the same decimal strings: the same doubles
    assert np.array_equal(a, scipy_coefficients.A)
    assert np.array_equal(c, scipy_coefficients.C)
    assert np.array_equal(d, scipy_coefficients.D)
    assert np.array_equal(a[END, :END], scipy_coefficients.B)


def test_the_coefficients_are_consistent():
    """Row sums are the stage times (c_i = sum_j a_ij), the weights sum to one, the matrix is explicit."""
    a, c, _ = dop853_coefficients()
    assert np.allclose(a.sum(axis=1), c, rtol=0, atol=1e-14)
    assert math.isclose(a[END, :END].sum(), 1.0, abs_tol=1e-14)
    assert np.all(np.triu(a) == 0.0)


def test_the_dense_output_is_hairers_contd8():
    """``dense`` in powers of s gives what dop853.f's CONTD8 gives from its CONT array, at the step's
    ends the step's start and new state."""
    rng = np.random.default_rng(4)
    a, _, d = dop853_coefficients()
    tab = dop853_tableau()
    k, y0, h = rng.normal(size=(STAGES, 3)), rng.normal(size=3), 0.37
    y1 = y0 + h * a[END, :END] @ k[:END]
    ydiff, bspl = y1 - y0, h * k[0] - (y1 - y0)
    cont = [y0, ydiff, bspl, ydiff - h * k[END] - bspl, *(h * (d @ k))]
    for s in (0.0, 0.1, 0.5, 0.83, 1.0):
        s1 = 1.0 - s
        contd8 = cont[0] + s * (cont[1] + s1 * (cont[2] + s * (cont[3] + s1 * (
            cont[4] + s * (cont[5] + s1 * (cont[6] + s * cont[7]))))))
        ours = y0 + h * k.T @ tab.dense @ (s ** np.arange(1, DEGREE + 1))
        assert np.allclose(ours, contd8, rtol=0, atol=1e-12)
    assert np.allclose(y0 + h * k.T @ tab.dense.sum(axis=1), y1, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("name", "rows", "expected"),
    [("a21", range(2, 17), (2, 1)), ("a111", range(2, 17), (11, 1)), ("a1110", range(2, 17), (11, 10)),
     ("a1514", range(2, 17), (15, 14)), ("d410", range(4, 8), (4, 10)), ("d716", range(4, 8), (7, 16))],
)
def test_coefficient_names_are_read_as_hairer_numbers_them(name, rows, expected):
    assert _indices(name, rows) == expected
