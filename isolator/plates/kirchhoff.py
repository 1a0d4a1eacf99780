"""The free-free bending modes of a rectangular Kirchhoff plate with rotatory inertia, by scikit-fem.

The plate lies in ``-lx/2 <= x <= lx/2``, ``-ly/2 <= y <= ly/2`` (its mid-surface, centre at the origin).
Bending strain energy ``D/2 int (1 - nu) w_,ab w_,ab + nu (lap w)^2 dA`` and kinetic energy
``1/2 int mu w'^2 + mu t^2/12 |grad w'|^2 dA`` (``mu`` the mass per area; the second term is the rotatory
inertia of the sections, which makes the plate's rigid rotations carry the box's inertia exactly), on a
mesh of Argyris triangles (quintic, C1: the exact free-edge conditions come out natural and converged
frequencies need few elements). The problem is solved in lengths scaled by the longer side and energies
by ``D`` and ``mu``, so that the matrices are well conditioned whatever the units.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.linalg import eigsh

from isolator.errors import ParameterError

__all__ = ["BendingModes", "bending_modes"]

#: the rigid bending motions (w = 1, x, y) the free plate's finite-element space contains
RIGID_BENDING = 3


@dataclass(frozen=True)
class BendingModes:
    """The elastic bending modes of a free plate and how to evaluate them anywhere on it.

    Attributes
    ----------
    frequency_hz : numpy.ndarray
        Natural frequencies (n,), Hz, ascending.
    vectors : numpy.ndarray
        The finite-element coefficients (dofs, n) of the scaled problem, mass-normalised there.
    scale : float
        The longer side ``L``, m: the mesh's coordinates are ``x / L``.
    amplitude : float
        ``1 / sqrt(mu L^2)``, 1/sqrt(kg): a scaled shape times it is the physical, mass-normalised one.
    basis : object
        The scikit-fem basis of the scaled mesh.
    """

    frequency_hz: np.ndarray
    vectors: np.ndarray
    scale: float
    amplitude: float
    basis: Any

    def evaluate(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The modes' deflection ``w`` [m/sqrt(kg)] and slopes ``dw/dx``, ``dw/dy`` [1/sqrt(kg)] at points.

        Parameters
        ----------
        x, y : numpy.ndarray
            Coordinates (N,) on the plate, m.

        Returns
        -------
        tuple of numpy.ndarray
            ``w``, ``dw/dx``, ``dw/dy``, each (n, N).
        """
        value, dx, dy = _probes(self.basis, np.vstack([x, y]) / self.scale)
        a = self.amplitude
        return ((value @ self.vectors).T * a, (dx @ self.vectors).T * a / self.scale,
                (dy @ self.vectors).T * a / self.scale)


def bending_modes(lx: float, ly: float, thickness: float, mass: float, rigidity: float, poisson: float,
                  count: int, elements: int) -> BendingModes:
    """The lowest ``count`` elastic bending modes of a free rectangular plate.

    Parameters
    ----------
    lx, ly, thickness : float
        The plate's sides and thickness, m.
    mass : float
        Its mass, kg (spread evenly: ``mu = mass / (lx ly)``).
    rigidity : float
        Its bending rigidity ``D``, N m.
    poisson : float
        Poisson's ratio.
    count : int
        Elastic modes wanted.
    elements : int
        Element divisions along the longer side (the shorter one in proportion, at least 2); each
        rectangle is two Argyris triangles.

    Returns
    -------
    BendingModes
        The modes, mass-normalised with the plate's mass (translation and rotatory inertia).
    """
    try:
        from skfem import Basis, BilinearForm, ElementTriArgyris, MeshTri
        from skfem.helpers import dd, ddot, dot, grad, trace
    except ImportError:
        raise ParameterError("plate modes need scikit-fem: pip install 'isolator[plate]'") from None
    scale = max(lx, ly)
    nx = max(2, round(elements * lx / scale))
    ny = max(2, round(elements * ly / scale))
    mesh = MeshTri.init_tensor(np.linspace(-lx / 2, lx / 2, nx + 1) / scale,
                               np.linspace(-ly / 2, ly / 2, ny + 1) / scale)
    basis = Basis(mesh, ElementTriArgyris())
    rotatory = (thickness / scale) ** 2 / 12.0

    @BilinearForm
    def stiffness(u: Any, v: Any, w: Any) -> Any:
        return (1.0 - poisson) * ddot(dd(u), dd(v)) + poisson * trace(dd(u)) * trace(dd(v))

    @BilinearForm
    def inertia(u: Any, v: Any, w: Any) -> Any:
        return u * v + rotatory * dot(grad(u), grad(v))

    K = stiffness.assemble(basis)
    M = inertia.assemble(basis)
    wanted = count + RIGID_BENDING
    if wanted >= basis.N - 1:
        raise ParameterError(f"elements: {elements} gives {basis.N} degrees of freedom, too few for {count} "
                             "modes; give more elements")
    start = np.random.default_rng(0).standard_normal(basis.N)  # a fixed start: the same digits each run
    lam, vectors = eigsh(K, k=wanted, M=M, sigma=-1.0, which="LM", v0=start)
    order = np.argsort(lam)
    lam, vectors = lam[order][RIGID_BENDING:], vectors[:, order][:, RIGID_BENDING:]
    vectors = vectors / np.sqrt(np.einsum("ij,ij->j", vectors, M @ vectors))
    mu = mass / (lx * ly)
    omega = np.sqrt(np.maximum(lam, 0.0) * rigidity / (mu * scale**4))
    return BendingModes(omega / (2 * np.pi), vectors, scale, 1.0 / np.sqrt(mu * scale**2), basis)


def _probes(basis: Any, points: np.ndarray) -> tuple[csr_matrix, csr_matrix, csr_matrix]:
    """Matrices that give a finite-element function's value and gradient at ``points`` (2, N) from its
    coefficients (as scikit-fem's ``CellBasis.probes`` does for the value alone)."""
    cells = basis.mesh.element_finder(mapping=basis.mapping)(*points)
    local = basis.mapping.invF(points[:, :, np.newaxis], tind=cells)
    fields = [basis.elem.gbasis(basis.mapping, local, k, tind=cells)[0] for k in range(basis.Nbfun)]
    n = points.shape[1]
    rows = np.tile(np.arange(n), basis.Nbfun)
    cols = basis.element_dofs[:, cells].ravel()
    shape = (n, basis.N)

    def matrix(values: list[np.ndarray]) -> csr_matrix:
        return csr_matrix((np.concatenate([v.ravel() for v in values]), (rows, cols)), shape=shape)

    return (matrix([np.asarray(f) for f in fields]), matrix([f.grad[0] for f in fields]),
            matrix([f.grad[1] for f in fields]))
