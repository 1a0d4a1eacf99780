"""The paper model reproduces the published planar equations, eq. (11) of Shin, Sun and Kim."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import make
from isolator import ParameterLayout, get_model


def _planar_scenario(k: float, c: float, L: float, hs: float, h: float):
    half = [{"position": [x, y, -hs], "stiffness": [k / 2, 1e5, k / 2], "damping": [c / 2, 1e3, c / 2]}
            for x, y in ((L, 0.5), (-L, 0.5), (-L, -0.5), (L, -0.5))]
    return make({
        "name": "planar",
        "table": {"mass": 4400.0, "inertia": [800.0, 1500.0, 1900.0]},
        "isolators": half,
        "carriages": [{"name": "m", "mass": 400.0, "axis": [1, 0, 0], "origin": [0, 0, h],
                       "profile": {"type": "sine", "amplitude": 0.7, "omega": 2.0}}],
    })


@pytest.mark.parametrize(("q", "qd", "qdd"), [(0.3, 0.2, -0.5), (-0.7, -1.1, 2.8), (0.0, 0.0, 0.0)])
def test_planar_matrices_equal_eq_11(q, qd, qdd):
    k, c, L, hs, h, g = 5.7e5, 5.7e3, 1.0, 0.15, 0.17, 9.81
    M_t, m, I = 4400.0, 400.0, 1500.0
    sc = _planar_scenario(k, c, L, hs, h)
    layout = ParameterLayout.of(sc)
    model = get_model(layout, "paper")
    Mo, Co, Ko, Fo = (np.asarray(a, float) for a in model.linear_matrices([q, qd, qdd], layout.pack(sc)))
    # paper coordinates (X, Y, theta) are ours (x, z, -ry): rows and columns alike
    T = np.zeros((6, 3))
    T[0, 0], T[2, 1], T[4, 2] = 1.0, 1.0, -1.0
    Mp, Cp, Kp, Fp = T.T @ Mo @ T, T.T @ Co @ T, T.T @ Ko @ T, T.T @ Fo.ravel()

    M11 = np.array([[M_t + m, 0, -m * h], [0, M_t + m, m * q], [-m * h, m * q, I + m * h**2 + m * q**2]])
    C11 = np.array([[2 * c, 0, 2 * c * hs], [0, 2 * c, 2 * m * qd],
                    [2 * c * hs, 0, 2 * c * (L**2 + hs**2) + 2 * m * q * qd]])
    K11 = np.array([[2 * k, 0, 2 * k * hs], [0, 2 * k, m * qdd],
                    [2 * k * hs, 0, 2 * k * (L**2 + hs**2) - m * g * h]])
    # eq. (11) measures Y from the table's own rest, so its F lacks the table's weight
    F11 = np.array([-m * qdd, -m * g - M_t * g, m * h * qdd - m * g * q])
    np.testing.assert_allclose(Mp, M11, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(Cp, C11, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(Kp, K11, rtol=1e-12, atol=1e-6)
    np.testing.assert_allclose(Fp, F11, rtol=1e-12, atol=1e-9)
