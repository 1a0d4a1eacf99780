"""Issue 40, item 4: the free-free modes of a rectangular top (``isolator.plate_modes``) against published and
independently computed frequencies, the rigid modes' mass and inertia, the mass normalisation by an independent
quadrature, and the rotations' sign convention against a 3-D solid."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.polynomial import legendre
from scipy.integrate import simpson
from scipy.linalg import eigh

from isolator import ParameterError, plate_modes
from isolator.plates import check_plate_arguments, rigid_modes
from isolator.plates.solid import solid_modes

E, NU, RHO = 70e9, 0.3, 2700.0  # aluminium


def _rigidity(t: float, young: float = E, nu: float = NU) -> float:
    return young * t**3 / (12 * (1 - nu**2))


def test_a_free_square_plate_has_leissas_frequencies():
    """Leissa, Vibration of Plates (NASA SP-160, 1969), free-free square, nu = 0.3: 13.47, 19.60, 24.27."""
    a, t = 1.0, 0.001
    top = plate_modes((a, a, t), RHO * t * a * a, E, NU, count=3)
    lam = 2 * np.pi * top.frequency_hz[6:] * a**2 * np.sqrt(RHO * t / _rigidity(t))
    np.testing.assert_allclose(lam, [13.47, 19.60, 24.27], rtol=1e-2)
    np.testing.assert_allclose(lam, [13.468, 19.596, 24.270], rtol=1e-3)  # converged: within the table's digits


def _ritz(lx: float, ly: float, t: float, n: int = 14) -> np.ndarray:
    """Free-free Kirchhoff plate by Rayleigh-Ritz on products of Legendre polynomials (independent of any
    finite element): angular frequencies of the elastic modes, rad/s, with the rotatory inertia."""
    xi, wq = legendre.leggauss(2 * n + 4)
    eye = np.eye(n)
    p = np.array([legendre.legval(xi, eye[i]) for i in range(n)])
    d1 = np.array([legendre.legval(xi, legendre.legder(eye[i], 1)) for i in range(n)])
    d2 = np.array([legendre.legval(xi, legendre.legder(eye[i], 2)) for i in range(n)])

    def gram(f, g):
        return (f * wq) @ g.T

    e0, e1, e2, e20 = gram(p, p), gram(d1, d1), gram(d2, d2), gram(d2, p)
    sx, sy = 2 / lx, 2 / ly  # d/dx = sx d/dxi
    area = lx * ly / 4
    D, mu = _rigidity(t), RHO * t
    K = D * area * (sx**4 * np.kron(e2, e0) + sy**4 * np.kron(e0, e2)
                    + NU * sx**2 * sy**2 * (np.kron(e20, e20.T) + np.kron(e20.T, e20))
                    + 2 * (1 - NU) * sx**2 * sy**2 * np.kron(e1, e1))
    M = mu * area * (np.kron(e0, e0) + t**2 / 12 * (sx**2 * np.kron(e1, e0) + sy**2 * np.kron(e0, e1)))
    lam = eigh(K, M, eigvals_only=True)
    return np.sqrt(np.abs(lam[3:]))


def test_a_rectangular_plate_matches_an_independent_ritz_solution():
    lx, ly, t = 2.0, 1.0, 0.02
    top = plate_modes((lx, ly, t), RHO * lx * ly * t, E, NU, count=8)
    ritz = _ritz(lx, ly, t)[:8] / (2 * np.pi)
    np.testing.assert_allclose(top.frequency_hz[6:], ritz, rtol=2e-3)
    assert np.all(ritz >= top.frequency_hz[6:] * (1 - 1e-6))  # Ritz bounds from above: both converge there


def _rigid_fit(nodes: np.ndarray, u: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """The contract's check: each rigid mode fitted as u = v + w x p; the body's mass, mass centre and
    inertia (about the origin) from sum q q^T = M^-1, q = (v, w)."""
    n = len(nodes)
    rows = np.zeros((3 * n, 6))
    for k in range(3):
        rows[k::3, k] = 1.0
        rows[k::3, 3:] = np.cross(np.eye(3)[k], nodes) * -1.0  # (w x p)_k = -(e_k x p) . w
    q = np.array([np.linalg.lstsq(rows, mode.ravel(), rcond=None)[0] for mode in u])
    m6 = np.linalg.inv(q.T @ q)
    mass = np.trace(m6[:3, :3]) / 3
    skew = m6[:3, 3:] / mass  # -[c]x: the momentum of a turn w about the origin is m w x c
    centre = np.array([skew[1, 2], skew[2, 0], skew[0, 1]])
    return mass, centre, m6[3:, 3:]


@pytest.mark.parametrize("model", ["plate", "solid"])
def test_the_written_rigid_modes_recover_the_box(model, tmp_path):
    size, mass = (2.0, 1.0, 0.3), 4400.0
    path = plate_modes(size, mass, 50e9, 0.25, count=2, model=model, grid=(9, 5)).to_csv(tmp_path / "top.csv")
    data = np.genfromtxt(path, delimiter=",", names=True)
    assert path.read_text().splitlines()[0].startswith("mode,frequency_hz,damping,x,y,z,ux,uy,uz")
    rigid = data[data["frequency_hz"] < 1.0]
    nodes = np.column_stack([rigid[k][rigid["mode"] == 1] for k in "xyz"])
    u = np.array([np.column_stack([rigid[k][rigid["mode"] == i] for k in ("ux", "uy", "uz")]) for i in range(1, 7)])
    m, c, inertia = _rigid_fit(nodes, u)
    lx, ly, t = size
    assert m == pytest.approx(mass, rel=1e-6)
    np.testing.assert_allclose(c, 0.0, atol=1e-9)
    np.testing.assert_allclose(inertia, np.diag([ly**2 + t**2, lx**2 + t**2, lx**2 + ly**2]) * mass / 12, rtol=1e-6,
                               atol=1e-6)
    assert len(np.unique(data["mode"])) == 8
    assert np.all(np.isnan(data["damping"]))


@pytest.fixture(scope="module")
def fine():
    """A 2:1 steel-like top's plate modes on a fine grid for Simpson's rule."""
    size, mass = (2.0, 1.0, 0.1), 1500.0
    return size, mass, plate_modes(size, mass, 200e9, 0.3, count=6, grid=(161, 81))


def test_mass_normalised_and_orthogonal_to_the_rigid_modes_by_an_independent_quadrature(fine):
    """phi^T M phi = 1 with the plate's mass (translation and rotatory inertia), by Simpson's rule on a fine
    grid of the modes' values (not the finite elements' quadrature); the elastic modes are orthogonal in
    mass to each other and to the box's rigid modes (the table's mean axes)."""
    (lx, ly, t), mass, top = fine
    mu = mass / (lx * ly)
    nx, ny = 161, 81
    x = np.linspace(-lx / 2, lx / 2, nx)
    y = np.linspace(-ly / 2, ly / 2, ny)

    def integral(f):
        return simpson(simpson(f.reshape(ny, nx), x=x, axis=1), x=y)

    e = top.elastic
    w, rot = top.translations[e, :, 2], top.rotations[e]
    gram = np.array([[integral(mu * w[i] * w[j] + mu * t**2 / 12 * (rot[i] * rot[j]).sum(axis=1))
                      for j in range(len(w))] for i in range(len(w))])
    np.testing.assert_allclose(gram, np.eye(len(w)), atol=2e-4)
    X, Y = top.nodes[:, 0], top.nodes[:, 1]
    for i in range(len(w)):  # translation z, turns about x (w = y, theta_x = 1) and about y (w = -x, theta_y = 1)
        assert abs(integral(mu * w[i])) < 1e-4 * np.sqrt(mass)
        assert abs(integral(mu * (w[i] * Y + t**2 / 12 * rot[i, :, 0]))) < 1e-4 * np.sqrt(mass)
        assert abs(integral(mu * (-w[i] * X + t**2 / 12 * rot[i, :, 1]))) < 1e-4 * np.sqrt(mass)


def test_rotations_are_the_slopes_with_the_contracts_sign(fine):
    """theta = (dw/dy, -dw/dx, 0), so that a face at z moves by u + theta x (0, 0, z) = (-z w_x, -z w_y, w)."""
    (lx, ly, _), _, top = fine
    nx, ny = 161, 81
    for i in range(6, 9):
        w = top.translations[i, :, 2].reshape(ny, nx)
        dwdy, dwdx = np.gradient(w, ly / (ny - 1), lx / (nx - 1))
        scale = np.abs(top.rotations[i]).max()
        inner = (slice(2, -2), slice(2, -2))
        np.testing.assert_allclose(top.rotations[i, :, 0].reshape(ny, nx)[inner], dwdy[inner], atol=2e-3 * scale)
        np.testing.assert_allclose(top.rotations[i, :, 1].reshape(ny, nx)[inner], -dwdx[inner], atol=2e-3 * scale)
        assert np.all(top.rotations[i, :, 2] == 0)


def test_a_thin_solid_has_the_plates_modes_and_its_faces_move_as_the_rotations_say():
    """The 3-D solid, independent of the plate model, tends to it for a thin top; its top face's in-plane
    translation is the plate's u + theta x (0, 0, t/2)."""
    size, mass = (1.0, 1.0, 0.02), RHO * 0.02
    plate = plate_modes(size, mass, E, NU, count=3, grid=(9, 9))
    solid = plate_modes(size, mass, E, NU, count=3, grid=(9, 9), model="solid")
    np.testing.assert_allclose(solid.frequency_hz[6:], plate.frequency_hz[6:], rtol=1e-2)
    top = solid.nodes[:, 2] > 0
    np.testing.assert_allclose(solid.nodes[top], plate.nodes + np.array([0.0, 0.0, 0.01]))
    for i in range(6, 9):
        face = plate.translations[i] + np.cross(plate.rotations[i], [0.0, 0.0, 0.01])
        np.testing.assert_allclose(solid.translations[i][top], face, atol=0.03 * np.abs(face).max())


def test_the_solid_is_mass_normalised_by_an_independent_quadrature():
    lx, ly, t, mass = 2.0, 1.0, 0.3, 4400.0
    modes = solid_modes(lx, ly, t, mass, 50e9, 0.25, count=3, elements=8)
    axes = [np.linspace(-s / 2, s / 2, n) for s, n in ((lx, 41), (ly, 21), (t, 9))]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    u = modes.evaluate(grid).reshape(3, 41, 21, 9, 3)
    rho = mass / (lx * ly * t)
    gram = np.einsum("iabck,jabck->ijabc", u, u)
    for x in reversed(axes):  # z, then y, then x
        gram = simpson(gram, x=x, axis=-1)
    np.testing.assert_allclose(rho * gram, np.eye(3), atol=2e-3)


def test_a_honeycomb_top_is_its_face_sheets_equivalent_plate():
    size, mass, tf = (1.2, 0.9, 0.2), 200.0, 0.005
    honeycomb = plate_modes(size, mass, E, NU, count=3, honeycomb=tf)
    d = E / (1 - NU**2) * (tf**3 / 6 + tf * (size[2] - tf) ** 2 / 2)
    same = plate_modes(size, mass, 12 * d * (1 - NU**2) / size[2] ** 3, NU, count=3)
    np.testing.assert_allclose(honeycomb.frequency_hz, same.frequency_hz, rtol=1e-7)
    np.testing.assert_allclose(honeycomb.translations, same.translations, atol=1e-6 * np.abs(same.translations).max())


def test_count_and_max_frequency_choose_the_modes():
    size, mass = (2.0, 1.0, 0.3), 4400.0
    top = plate_modes(size, mass, 50e9, 0.25, count=6, max_frequency=520.0, grid=(5, 3))
    np.testing.assert_allclose(top.frequency_hz[6:], [193.2, 242.5, 509.2, 517.3], atol=0.1)
    with pytest.raises(ParameterError, match=r"^max_frequency: no elastic mode up to 100 Hz \(the first is at 193"):
        plate_modes(size, mass, 50e9, 0.25, max_frequency=100.0)
    with pytest.raises(ParameterError, match=r"^size: the first elastic mode is at .* below 1 Hz"):
        plate_modes((50.0, 50.0, 0.001), 100.0, 1e6, 0.25, count=1)


def test_rigid_modes_move_a_point_as_a_turn_does():
    u, r = rigid_modes(np.array([[0.5, -0.25, 0.1]]), 10.0, (1.0, 0.5, 0.2))
    np.testing.assert_allclose(u[:3, 0], np.eye(3) / np.sqrt(10.0))
    for k in range(3):
        np.testing.assert_allclose(u[3 + k, 0], np.cross(r[3 + k, 0], [0.5, -0.25, 0.1]))
    assert r[:3].max() == 0.0


BAD = [
    ({"size": (2.0, 0.0, 0.3)}, r"^size: every entry must be positive"),
    ({"size": (2.0, 1.0)}, r"^size: must be 3 numbers"),
    ({"mass": 0.0}, r"^mass: must be positive"),
    ({"young": -5.0}, r"^young: must be positive"),
    ({"poisson": 0.5}, r"^poisson: must lie between -1 and 0.5"),
    ({"count": 0}, r"^count: must be a whole number >= 1"),
    ({"count": 2.5}, r"^count: must be a whole number"),
    ({"elements": 1}, r"^elements: must be a whole number >= 2"),
    ({"max_frequency": float("inf")}, r"^max_frequency: must be finite"),
    ({"honeycomb": 0.2}, r"^honeycomb: a face sheet must be thinner than half the thickness"),
    ({"honeycomb": 0.01, "model": "solid"}, r"^honeycomb: a honeycomb top is an equivalent plate"),
    ({"model": "shell"}, r"^model: must be one of plate, solid"),
    ({"grid": (1, 5)}, r"^grid: two whole numbers of nodes >= 2"),
]


@pytest.mark.parametrize(("change", "message"), BAD, ids=[m.split(":")[0][1:] for _, m in BAD])
def test_bad_arguments_are_one_line_naming_them(change, message):
    arguments = {"size": (2.0, 1.0, 0.3), "mass": 4400.0, "young": 50e9, "poisson": 0.25} | change
    with pytest.raises(ParameterError, match=message) as caught:
        plate_modes(**arguments)
    assert "\n" not in str(caught.value)


@given(st.one_of(st.floats(max_value=-1.0), st.floats(min_value=0.5)))
def test_every_poisson_ratio_outside_the_open_range_is_refused(nu):
    with pytest.raises(ParameterError, match=r"^poisson: must (lie between|be finite)"):
        check_plate_arguments((2.0, 1.0, 0.3), 4400.0, 50e9, nu)


@given(st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=3, max_size=3)
       .filter(lambda s: min(s) <= 0), st.floats(max_value=0.0, allow_nan=False, allow_infinity=False))
def test_every_non_positive_size_or_mass_is_refused(size, mass):
    with pytest.raises(ParameterError, match=r"^size: every entry must be positive"):
        check_plate_arguments(size, 4400.0, 50e9, 0.25)
    with pytest.raises(ParameterError, match=r"^mass: must be positive"):
        check_plate_arguments((2.0, 1.0, 0.3), mass, 50e9, 0.25)
