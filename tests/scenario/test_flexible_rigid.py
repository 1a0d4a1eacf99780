"""The six rigid modes of a modal file: the fit recovers the box's mass, mass centre and inertia (any origin,
any orientation of its principal axes), and a file in mm, in tonnes or about another origin is refused naming
both values and the likely cause."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from isolator.errors import ScenarioError
from isolator.scenario.flexible import check_rigid, fit_rigid, load_modal_data, rigid_properties
from isolator.scenario.flexible.synthetic import box_rigid_modes, synthetic_top
from isolator.scenario.flexible.writing import write_modal_csv

SIZE = (2.0, 1.0, 0.2)
MASS = 1000.0
BOX = MASS * np.array([SIZE[1] ** 2 + SIZE[2] ** 2, SIZE[0] ** 2 + SIZE[2] ** 2, SIZE[0] ** 2 + SIZE[1] ** 2]) / 12


def _rotation(angles: tuple[float, float, float]) -> np.ndarray:
    a, b, c = angles
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    return rz @ ry @ rx


def test_the_box_mass_centre_and_inertia_come_back_from_its_rigid_modes():
    top = synthetic_top(SIZE, MASS, frequencies=(100.0,))
    v, w, residual = fit_rigid(top.nodes, top.translations[:6], top.rotations[:6])
    assert residual.max() < 1e-12
    rigid = rigid_properties(v, w)
    assert rigid.mass == pytest.approx(MASS, rel=1e-12)
    np.testing.assert_allclose(rigid.centre, 0.0, atol=1e-12)
    np.testing.assert_allclose(rigid.inertia, np.diag(BOX), rtol=1e-12, atol=1e-9)


coordinate = st.floats(-3.0, 3.0, allow_nan=False)
angle = st.floats(-np.pi, np.pi, allow_nan=False)


@settings(max_examples=40, deadline=None)
@given(centre=st.tuples(coordinate, coordinate, coordinate), angles=st.tuples(angle, angle, angle),
       rotations=st.booleans())
def test_any_centre_and_principal_axes_come_back(centre, angles, rotations):
    """Rigid modes about principal axes ``R e_k`` through ``c``: the fit gives ``m``, ``c`` and ``R diag(I) R^T``,
    with or without the rotations in the fit."""
    rot = _rotation(angles)
    nodes = synthetic_top(SIZE, MASS, frequencies=(), rigid=False).nodes @ rot.T + np.array(centre)
    u, r = box_rigid_modes(nodes @ rot, MASS, BOX, np.array(centre) @ rot)  # in the principal frame
    u, r = u @ rot.T, r @ rot.T  # back to the file's axes
    v, w, _ = fit_rigid(nodes, u, r if rotations else None)
    rigid = rigid_properties(v, w)
    assert rigid.mass == pytest.approx(MASS, rel=1e-9)
    np.testing.assert_allclose(rigid.centre, centre, atol=1e-9)
    np.testing.assert_allclose(rigid.inertia, rot @ np.diag(BOX) @ rot.T, rtol=1e-9, atol=1e-6)


@settings(max_examples=15, deadline=None)
@given(modes=st.permutations(range(6)), mix=st.lists(st.floats(-1.0, 1.0), min_size=9, max_size=9))
def test_the_mass_matrix_does_not_depend_on_which_orthonormal_rigid_modes_the_file_gives(modes, mix):
    """Any orthonormal recombination of the six rigid modes (a solver's degenerate eigenvectors) gives the same
    body: sum v v^T and sum w w^T are invariant."""
    top = synthetic_top(SIZE, MASS, frequencies=(), centre=(0.1, -0.05, 0.02))
    q, _ = np.linalg.qr(np.eye(6) + 0.5 * np.pad(np.reshape(mix, (3, 3)), ((0, 3), (3, 0))))
    u = np.einsum("ij,jnk->ink", q, top.translations[list(modes)])
    r = np.einsum("ij,jnk->ink", q, top.rotations[list(modes)])
    rigid = rigid_properties(*fit_rigid(top.nodes, u, r)[:2])
    assert rigid.mass == pytest.approx(MASS, rel=1e-9)
    np.testing.assert_allclose(rigid.centre, (0.1, -0.05, 0.02), atol=1e-9)


def _file(tmp_path, name="top.csv", length=1.0, mass_unit=1.0, centre=(0.0, 0.0, 0.0)):
    """The synthetic top written as if in other units: lengths in ``length`` file units per m, masses in
    ``mass_unit`` kg per file unit (shapes in length/sqrt(mass))."""
    top = synthetic_top(SIZE, MASS, frequencies=(150.0, 200.0), centre=centre)
    scale = length / np.sqrt(1.0 / mass_unit)
    return write_modal_csv(tmp_path / name, top.frequencies, top.nodes * length, top.translations * scale,
                           top.rotations / np.sqrt(1.0 / mass_unit))


def _refusal(path, mass=MASS, largest=2.0, origin=(0.0, 0.0, 0.0)) -> str:
    data = load_modal_data(path, thickness=SIZE[2], origin=origin)
    with pytest.raises(ScenarioError) as info:
        check_rigid(data.rigid, mass, largest, f"table.flexible.modes: '{path}'", origin)
    return str(info.value)


def test_a_file_in_mm_is_refused_naming_both_masses(tmp_path):
    text = _refusal(_file(tmp_path, length=1000.0))
    assert "0.001 kg" in text
    assert "1000 kg" in text
    assert "lengths in mm" in text
    assert "top.csv" in text


def test_a_file_in_tonnes_is_refused(tmp_path):
    text = _refusal(_file(tmp_path, mass_unit=1000.0))
    assert "1 kg" in text
    assert "[table] mass is 1000 kg" in text
    assert "tonnes" in text


def test_a_file_in_mm_and_tonnes_is_refused(tmp_path):
    assert "mm and masses in tonnes" in _refusal(_file(tmp_path, length=1000.0, mass_unit=1000.0))


def test_a_file_about_another_origin_is_refused_and_the_origin_key_mends_it(tmp_path):
    path = _file(tmp_path, centre=(1.0, 0.5, 0.1))  # about a corner
    text = _refusal(path)
    assert "mass centre at [1, 0.5, 0.1] m" in text
    assert "origin = [-1, -0.5, -0.1]" in text
    data = load_modal_data(path, thickness=SIZE[2], origin=(-1.0, -0.5, -0.1))
    check_rigid(data.rigid, MASS, 2.0, "x")
    np.testing.assert_allclose(data.rigid.centre, 0.0, atol=1e-12)


def test_one_percent_is_the_limit(tmp_path):
    path = _file(tmp_path)
    data = load_modal_data(path, thickness=SIZE[2])
    check_rigid(data.rigid, MASS * 1.0099, 2.0, "x")
    assert "shapes not mass-normalised" in _refusal(path, mass=MASS * 1.02)
    data = load_modal_data(path, thickness=SIZE[2], origin=(0.0, 0.0199, 0.0))
    check_rigid(data.rigid, MASS, 2.0, "x")
    text = _refusal(path, origin=(0.0, 0.0201, 0.0))
    assert "mass centre at [0, 0.0201, 0] m" in text
    assert "0.0201 m from the table frame's origin" in text
    assert "within 1 % of the top's largest size 2 m = 0.02 m needed" in text
    assert "origin = [0, 0, 0]" in text


@pytest.mark.parametrize("keep", [1, 5, 7])
def test_one_to_five_or_more_than_six_rigid_modes_are_refused(tmp_path, keep):
    top = synthetic_top(SIZE, MASS, frequencies=(150.0,))
    u, r, f = top.translations, top.rotations, top.frequencies
    if keep == 7:
        u, r, f = np.concatenate([u[:1], u]), np.concatenate([r[:1], r]), np.concatenate([[0.0], f])
    else:
        u, r, f = u[6 - keep:], r[6 - keep:], f[6 - keep:]
    path = write_modal_csv(tmp_path / "top.csv", f, top.nodes, u, r)
    with pytest.raises(ScenarioError, match=rf"top.csv': {keep} modes below 1 Hz \(mode 1 \(line 2\)"):
        load_modal_data(path, thickness=0.2)


def test_a_file_without_rigid_modes_is_not_checked(tmp_path):
    top = synthetic_top(SIZE, MASS, frequencies=(150.0,), rigid=False)
    data = load_modal_data(write_modal_csv(tmp_path / "top.csv", top.frequencies, top.nodes, top.translations),
                           thickness=0.2)
    assert data.rigid is None
    assert data.n_modes == 1


def test_a_mode_below_1_hz_that_is_no_rigid_motion_is_refused(tmp_path):
    top = synthetic_top(SIZE, MASS, frequencies=(150.0, 200.0))
    u = top.translations[[0, 1, 2, 3, 4, 6, 7]]  # an elastic shape instead of the sixth rigid mode
    path = write_modal_csv(tmp_path / "top.csv", [0.0] * 6 + [200.0], top.nodes, u)
    with pytest.raises(ScenarioError, match=r"mode 6 \(line \d+\) \(0 Hz\) is no rigid motion"):
        load_modal_data(path, thickness=0.2)


@settings(max_examples=15, deadline=None)
@given(centre=st.tuples(coordinate, coordinate, coordinate))
def test_a_file_about_any_origin_with_the_origin_key_is_the_centred_file(centre):
    """The same top written about another origin and read with ``origin`` putting it back: the same rigid body
    and the same face translations at every point of the table frame."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as folder:
        centred = _file(Path(folder), "a.csv")
        moved = _file(Path(folder), "b.csv", centre=centre)
        a = load_modal_data(centred, thickness=SIZE[2])
        b = load_modal_data(moved, thickness=SIZE[2], origin=tuple(-np.array(centre)))
    check_rigid(b.rigid, MASS, 2.0, "x")
    np.testing.assert_allclose(b.rigid.centre, 0.0, atol=1e-9)
    np.testing.assert_allclose(b.nodes, a.nodes, atol=1e-12)
    xy = np.random.default_rng(0).uniform((-1.0, -0.5), (1.0, 0.5), (20, 2))
    for face in ("top", "bottom"):
        np.testing.assert_allclose(b.translation(xy, face, "p"), a.translation(xy, face, "p"), atol=1e-12)
