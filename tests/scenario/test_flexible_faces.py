"""The faces of a bending top and their C1 (Clough-Tocher) interpolation: linear fields exact everywhere,
any field exact at the nodes, a smooth field to third order; a single layer's faces from its rotations; points
outside a face refused naming them; the data hashed by content."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.flexible import ModalData
from isolator.scenario.flexible.faces import FaceInterpolant


def _data(nodes, translations, rotations=None, thickness=0.2, path="top.csv"):
    n = len(translations)
    return ModalData(path=path, frequencies=np.linspace(100.0, 200.0, n), damping=np.full(n, 0.01), nodes=nodes,
                     translations=translations, rotations=rotations, thickness=thickness)


def _plate(nx, ny, z=(0.1, -0.1), lx=2.0, ly=1.0):
    x, y = np.meshgrid(np.linspace(-lx / 2, lx / 2, nx), np.linspace(-ly / 2, ly / 2, ny), indexing="ij")
    return np.vstack([np.column_stack([x.ravel(), y.ravel(), np.full(x.size, h)]) for h in z])


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31), coefficients=st.lists(st.floats(-5, 5), min_size=9, max_size=9))
def test_a_linear_field_is_exact_everywhere_on_scattered_nodes(seed, coefficients):
    rng = np.random.default_rng(seed)
    scattered = np.round(rng.uniform((-1, -0.5), (1, 0.5), (30, 2)), 6)  # a mesh's micrometres (rounded to nm)
    xy = np.vstack([[(-1, -0.5), (1, -0.5), (1, 0.5), (-1, 0.5)], scattered])
    c = np.reshape(coefficients, (3, 3))
    field = c[:, 0] + xy[:, :1] * c[:, 1] + xy[:, 1:] * c[:, 2]  # (k, 3)
    nodes = np.column_stack([xy, np.full(len(xy), 0.1)])
    nodes = np.vstack([nodes, nodes - (0, 0, 0.2)])
    data = _data(nodes, np.concatenate([field, field])[None])
    probe = rng.uniform((-1, -0.5), (1, 0.5), (50, 2))
    want = c[:, 0] + probe[:, :1] * c[:, 1] + probe[:, 1:] * c[:, 2]
    np.testing.assert_allclose(data.translation(probe, "top", "p")[:, 0], want, atol=1e-10 * (1 + np.abs(c).max()))


def test_a_cubic_field_is_exact_at_the_nodes():
    nodes = _plate(9, 5)
    x, y = nodes[:, 0], nodes[:, 1]
    field = np.column_stack([x**3 - 2 * x * y**2, y**3 + x**2, x * y])
    data = _data(nodes, field[None])
    for face, rows in (("top", nodes[:, 2] > 0), ("bottom", nodes[:, 2] < 0)):
        np.testing.assert_allclose(data.translation(nodes[rows, :2], face, "n")[:, 0], field[rows], atol=1e-12)


def test_a_smooth_field_converges_at_second_order():
    """sin(2x) cos(3y) on grids of spacing 4h, 2h, h: the largest error falls by about 4 per halving (a C1 cubic
    whose nodal gradients are estimated from the values, scipy's global estimate: second order)."""
    probe = np.random.default_rng(3).uniform((-0.95, -0.45), (0.95, 0.45), (400, 2))
    errors = []
    for n in (9, 17, 33):
        nodes = _plate(n, (n + 1) // 2)
        w = np.sin(2 * nodes[:, 0]) * np.cos(3 * nodes[:, 1])
        data = _data(nodes, np.column_stack([0 * w, 0 * w, w])[None])
        got = data.translation(probe, "top", "p")[:, 0, 2]
        errors.append(np.abs(got - np.sin(2 * probe[:, 0]) * np.cos(3 * probe[:, 1])).max())
    rates = np.log2(np.array(errors[:-1]) / errors[1:])
    assert errors[-1] < 2e-3
    assert np.all(rates > 1.8), (errors, rates)


def test_a_single_layer_gives_its_faces_from_the_rotations():
    nodes = _plate(5, 3, z=(0.0,))
    rng = np.random.default_rng(0)
    u, theta = rng.normal(size=(2, 1, len(nodes), 3))
    data = _data(nodes, u, theta, thickness=0.3)
    half = 0.15
    top = u[0] + np.column_stack([theta[0, :, 1] * half, -theta[0, :, 0] * half, 0 * theta[0, :, 2]])
    bottom = u[0] - np.column_stack([theta[0, :, 1] * half, -theta[0, :, 0] * half, 0 * theta[0, :, 2]])
    np.testing.assert_allclose(data.translation(nodes[:, :2], "top", "n")[:, 0], top, atol=1e-12)
    np.testing.assert_allclose(data.translation(nodes[:, :2], "bottom", "n")[:, 0], bottom, atol=1e-12)
    np.testing.assert_allclose(np.cross(theta[0], (0, 0, half)), top - u[0], atol=1e-12)  # theta x (0, 0, t/2)


def test_the_faces_are_the_nodes_within_1_mm_of_the_highest_and_lowest():
    nodes = _plate(5, 3, z=(0.1, -0.1))
    nodes = np.vstack([nodes, _plate(4, 2, z=(0.0995,), lx=1.5, ly=0.5)])  # within 1 mm: on the top face
    field = np.zeros((1, len(nodes), 3))
    field[0, :, 2] = np.where(nodes[:, 2] > 0, 1.0, -1.0)
    data = _data(nodes, field)
    np.testing.assert_allclose(data.translation([(0.1, 0.1)], "top", "p")[0, 0, 2], 1.0)
    assert data.face_for(0.001) == "top"
    assert data.face_for(-0.01) == "bottom"


def test_a_point_up_to_1_mm_outside_is_taken_at_the_outline_and_beyond_it_refused():
    nodes = _plate(5, 3)
    field = np.zeros((1, len(nodes), 3))
    field[0, :, 0] = nodes[:, 0]
    data = _data(nodes, field)
    np.testing.assert_array_equal(data.inside([(1.0009, 0.0), (1.0011, 0.0), (0.0, -0.5), (0.3, 0.2)], "top"),
                                  [True, False, True, True])
    assert data.translation([(1.0009, 0.2)], "top", "p")[0, 0, 0] == pytest.approx(1.0, abs=1e-8)
    with pytest.raises(ScenarioError) as info:
        data.translation([(0.0, 0.0), (1.002, 0.6)], "bottom", "carriages[0] (x-stage).feet[1]")
    assert str(info.value) == ("carriages[0] (x-stage).feet[1]: (x, y) = (1.002, 0.6) m lies 100 mm outside the "
                               "bottom face of the top's nodes in 'top.csv' (x -1 to 1 m, y -0.5 to 0.5 m; within "
                               "1 mm of their outline needed)")


def test_the_face_interpolant_alone_gives_distances_to_the_outline():
    square = np.array([(0, 0), (1, 0), (1, 1), (0, 1), (0.5, 0.5)], dtype=float)
    face = FaceInterpolant(square, square[:, :1])
    _, distance = face.nearest(np.array([(0.5, 0.5), (1.5, 0.5), (2.0, 2.0), (-0.1, 0.5)]))
    np.testing.assert_allclose(distance, [0.0, 0.5, np.sqrt(2), 0.1])


def test_bad_faces_and_points_are_refused():
    data = _data(_plate(3, 3), np.zeros((1, 18, 3)))
    with pytest.raises(ParameterError, match="face: must be 'top' or 'bottom'"):
        data.translation([(0, 0)], "side", "p")
    with pytest.raises(ParameterError, match=r"xy: must be finite \(x, y\) points"):
        data.translation([(0, 0, 0)], "top", "p")
    with pytest.raises(ScenarioError, match=r"'top.csv': translations must have the shape \(1, 18, 3\)"):
        _data(_plate(3, 3), np.zeros((1, 17, 3)))
    with pytest.raises(ScenarioError, match=r"'top.csv': frequencies must be finite"):
        ModalData("top.csv", [np.nan], [0.01], _plate(3, 3), np.zeros((1, 18, 3)), None, 0.2)


def test_modal_data_is_equal_and_hashed_by_content_and_pickles():
    nodes = _plate(5, 3)
    u = np.random.default_rng(0).normal(size=(2, len(nodes), 3))
    a, b = _data(nodes, u, path="a.csv"), _data(nodes.copy(), u.copy(), path="b.unv")
    assert a == b
    assert hash(a) == hash(b)
    assert a.digest == b.digest
    assert a != _data(nodes, u * 1.001)
    a.translation([(0, 0)], "top", "p")  # builds and caches an interpolant
    copy = pickle.loads(pickle.dumps(a))
    assert copy == a
    np.testing.assert_array_equal(copy.translation([(0.2, 0.1)], "top", "p"), a.translation([(0.2, 0.1)], "top", "p"))
    with pytest.raises(ValueError, match="read-only"):
        a.translations[0, 0, 0] = 1.0


def test_point_translation_is_the_mean_over_the_feet_on_the_face_of_the_position():
    nodes = _plate(5, 3)
    field = np.zeros((1, len(nodes), 3))
    field[0, :, 2] = nodes[:, 0] + 10 * (nodes[:, 2] < 0)
    data = _data(nodes, field)
    np.testing.assert_allclose(data.point_translation((0.2, 0.0, 0.3), [(-0.5, 0.0), (0.3, 0.1)], "p"),
                               [[0.0, 0.0, 0.1]], atol=1e-12)
    np.testing.assert_allclose(data.point_translation((0.2, 0.0, -0.3), None, "p"), [[0.0, 0.0, 10.2]], atol=1e-12)
