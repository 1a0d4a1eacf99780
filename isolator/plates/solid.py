"""The free-free modes of a rectangular block by 3-D linear elasticity, by scikit-fem.

The block fills ``|x| <= lx/2``, ``|y| <= ly/2``, ``|z| <= t/2``; isotropic, homogeneous; triquadratic
hexahedra (27 nodes), ``elements`` along the longer side, the other sides in proportion (at least two
layers through the thickness). Every elastic mode of the block comes out: bending, twisting, shear through
the thickness, and the in-plane ones. The problem is solved in lengths scaled by the longer side,
stiffness by ``E`` and mass by the density.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.sparse.linalg import eigsh

from isolator.errors import ParameterError

__all__ = ["SolidModes", "solid_modes"]

#: the rigid motions of a free solid
RIGID_SOLID = 6


@dataclass(frozen=True)
class SolidModes:
    """The elastic modes of a free block and how to evaluate them anywhere in it.

    Attributes
    ----------
    frequency_hz : numpy.ndarray
        Natural frequencies (n,), Hz, ascending.
    vectors : numpy.ndarray
        The finite-element coefficients (dofs, n) of the scaled problem, mass-normalised there.
    scale : float
        The longer side ``L``, m: the mesh's coordinates are ``x / L``.
    amplitude : float
        ``1 / sqrt(rho L^3)``, 1/sqrt(kg): a scaled shape times it is the physical, mass-normalised one.
    basis : object
        The scikit-fem basis of the scaled mesh.
    """

    frequency_hz: np.ndarray
    vectors: np.ndarray
    scale: float
    amplitude: float
    basis: Any

    def evaluate(self, points: np.ndarray) -> np.ndarray:
        """The modes' translations at points.

        Parameters
        ----------
        points : numpy.ndarray
            Positions (N, 3) in the block, m.

        Returns
        -------
        numpy.ndarray
            Translations (n, N, 3), m/sqrt(kg).
        """
        probes = self.basis.probes(np.asarray(points, dtype=float).T / self.scale).tocsr()
        values = (probes @ self.vectors).reshape(3, len(points), -1)
        return np.transpose(values, (2, 1, 0)) * self.amplitude


def solid_modes(lx: float, ly: float, thickness: float, mass: float, young: float, poisson: float, count: int,
                elements: int) -> SolidModes:
    """The lowest ``count`` elastic modes of a free, homogeneous rectangular block.

    Parameters
    ----------
    lx, ly, thickness : float
        The block's sides, m.
    mass : float
        Its mass, kg (density ``mass / (lx ly t)``).
    young : float
        Young's modulus, Pa.
    poisson : float
        Poisson's ratio.
    count : int
        Elastic modes wanted.
    elements : int
        Element divisions along the longer side.

    Returns
    -------
    SolidModes
        The modes, mass-normalised with the block's mass.
    """
    try:
        from skfem import Basis, BilinearForm, ElementHex2, ElementVector, MeshHex, asm
        from skfem.helpers import dot
        from skfem.models.elasticity import lame_parameters, linear_elasticity
    except ImportError:
        raise ParameterError("plate modes need scikit-fem: pip install 'isolator[plate]'") from None
    scale = max(lx, ly, thickness)
    divisions = [max(1, round(elements * side / scale)) for side in (lx, ly)]
    divisions.append(max(2, round(elements * thickness / scale)))
    mesh = MeshHex.init_tensor(*(np.linspace(-side / 2, side / 2, n + 1) / scale
                                 for side, n in zip((lx, ly, thickness), divisions, strict=True)))
    basis = Basis(mesh, ElementVector(ElementHex2()), intorder=4)

    @BilinearForm
    def inertia(u: Any, v: Any, w: Any) -> Any:
        return dot(u, v)

    K = asm(linear_elasticity(*lame_parameters(1.0, poisson)), basis)
    M = asm(inertia, basis)
    wanted = count + RIGID_SOLID
    if wanted >= basis.N - 1:
        raise ParameterError(f"elements: {elements} gives {basis.N} degrees of freedom, too few for {count} "
                             "modes; give more elements")
    start = np.random.default_rng(0).standard_normal(basis.N)  # a fixed start: the same digits each run
    lam, vectors = eigsh(K, k=wanted, M=M, sigma=-1.0, which="LM", v0=start)
    order = np.argsort(lam)
    lam, vectors = lam[order][RIGID_SOLID:], vectors[:, order][:, RIGID_SOLID:]
    vectors = vectors / np.sqrt(np.einsum("ij,ij->j", vectors, M @ vectors))
    density = mass / (lx * ly * thickness)
    omega = np.sqrt(np.maximum(lam, 0.0) * young / (density * scale**2))
    return SolidModes(omega / (2 * np.pi), vectors, scale, 1.0 / np.sqrt(density * scale**3), basis)
