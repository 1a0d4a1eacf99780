"""The elastic modes of a bending top in the one residual: their coordinates, and how carriages and forces couple.

The table's six coordinates are the top's mean axes; each kept free-free mode ``i`` adds a coordinate
``eta_i`` with modal mass 1, stiffness ``(2 pi f_i)^2`` and damping ``2 zeta_i (2 pi f_i)``
(``docs/scenario-format.md``, "A top that bends"). With mass-normalised free-free modes the top's own
inertia does not couple the rigid and elastic coordinates; what couples them:

* a force ``f`` (world axes) at a table point with elastic translation ``Phi eta`` (table frame) acts at
  ``R (p + Phi eta)`` and loads the modes with ``Phi^T R^T f``;
* a carriage riding the top at position ``d`` (table frame) moves with its feet's elastic translation
  ``e = Psi(q) eta``; its inertia and weight, Lagrange's ``sum m a . dr/d eta``, load the modes with
  ``Psi^T m (a - g)`` and the table with the reaction of ``m e''``, where
  ``e'' = Psi eta'' + 2 Psi' eta' + Psi'' eta`` holds the moving load's terms (``Psi' = dPsi/dq q'``).

Terms of second order in the small motions (products of the elastic coordinates with the table's rotation
rate, angular acceleration or acceleration, or with themselves) are dropped, as in a linear-elastic
floating-frame model: the mass matrix then depends on the carriages' positions only, and the carriages'
elastic terms are affine in ``(eta, eta', omega, g_body)`` (:func:`affine_carriage_terms`).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from isolator.model.blocks import solve_blocks
from isolator.model.flexible.structure import ElasticStructure

__all__ = ["ElasticState", "carriage_shapes", "carriage_terms", "modal_shapes", "solve_mass"]


@dataclass(frozen=True)
class ElasticState:
    """The elastic coordinates in a residual.

    Attributes
    ----------
    structure : ElasticStructure
    eta, rate : SX (modes,)
        Modal coordinates and their rates.
    accel : SX (modes,)
        Their accelerations (symbols the mass matrix is taken with, or zeros).
    terms : tuple of SX
        The carriages' terms (translation (3,), rotation (3,), modal (modes,)) of :func:`carriage_terms`.
    """

    structure: ElasticStructure
    eta: ca.SX
    rate: ca.SX
    accel: ca.SX
    terms: tuple[ca.SX, ca.SX, ca.SX]

    def modal_rows(self, forces: ca.SX) -> ca.SX:
        """The modes' equations: ``eta'' + 2 zeta w eta' + w^2 eta + carriages' terms - forces = 0``."""
        omega = 2.0 * np.pi * np.asarray(self.structure.frequencies)
        zeta = np.asarray(self.structure.damping)
        return (self.accel + ca.DM(2.0 * zeta * omega) * self.rate + ca.DM(omega**2) * self.eta
                + self.terms[2] - forces)


def modal_shapes(flat: tuple[tuple[float, ...], ...], structure: ElasticStructure) -> list[ca.DM]:
    """Constant (3, modes) shapes of attachment points."""
    return [ca.DM(structure.shape_matrix(s)) for s in flat]


def _clenshaw(coeffs: np.ndarray, s: ca.SX) -> ca.SX:
    """``sum_k C_k T_k(s)`` for constant (degree + 1, 3, modes) coefficients (Clenshaw's recurrence)."""
    nm = coeffs.shape[2]
    b1, b2 = ca.SX.zeros(3, nm), ca.SX.zeros(3, nm)
    for k in range(coeffs.shape[0] - 1, 0, -1):
        b1, b2 = ca.DM(coeffs[k]) + 2 * s * b1 - b2, b1
    return ca.DM(coeffs[0]) + s * b1 - b2


def carriage_shapes(structure: ElasticStructure, c: ca.SX, n: int) -> dict[int, tuple[ca.SX, ca.SX, ca.SX]]:
    """``Psi, dPsi/dt, d2Psi/dt2`` (each (3, modes)) of every root carriage, from the carriages' inputs ``c``
    (q, q', q'', 3 n): the Chebyshev series and its derivatives' series (``numpy.polynomial.chebyshev.chebder``)
    by Clenshaw's recurrence."""
    out: dict[int, tuple[ca.SX, ca.SX, ca.SX]] = {}
    nm = structure.n_modes
    for shape in {s.root: s for s in structure.carriages}.values():
        r = shape.root
        q, qd, qdd = c[r], c[n + r], c[2 * n + r]
        lo, hi = shape.domain
        coeffs, first, second = shape.series(nm)
        s_sym = ca.SX.sym("s")
        fn = ca.Function("psi", [s_sym], [_clenshaw(coeffs, s_sym), _clenshaw(first, s_sym),
                                          _clenshaw(second, s_sym)])
        psi, dpsi, ddpsi = fn((2 * q - lo - hi) / (hi - lo))
        out[r] = (psi, dpsi * qd, ddpsi * qd * qd + dpsi * qdd)
    return out


def carriage_terms(
    structure: ElasticStructure,
    paths: list[tuple[ca.SX, ca.SX, ca.SX]],
    masses: ca.SX,
    shapes: dict[int, tuple[ca.SX, ca.SX, ca.SX]],
    eta: ca.SX,
    rate: ca.SX,
    accel: ca.SX,
    acc_body: ca.SX,
    alpha_body: ca.SX,
    w_body: ca.SX,
    g_body: ca.SX,
    g_world: ca.SX,
) -> tuple[ca.SX, ca.SX, ca.SX]:
    """The carriages' elastic terms of the residual (table frame), to first order in the small motions.

    Parameters
    ----------
    paths : list of (d, d', d'')
        Each carriage's rigid position in the table frame from the mass centre and its rates [m, m/s, m/s^2].
    masses : SX (n,)
        [kg].
    shapes : dict
        :func:`carriage_shapes`.
    eta, rate, accel : SX (modes,)
        Modal coordinates, rates, accelerations.
    acc_body, alpha_body, w_body : SX (3,)
        The table's acceleration [m/s^2], angular acceleration [rad/s^2] and rate [rad/s], table frame.
    g_body, g_world : SX (3,)
        Gravity in the table frame and in the world [m/s^2] (the latter where it multiplies ``eta``).

    Returns
    -------
    tuple of SX
        Added to the translation rows [N], the rotation rows [N m] (about the mass centre), and the modal
        rows (without the modes' own stiffness, damping and the forces at attachment points).
    """
    nm = structure.n_modes
    trans, rot, modal = ca.SX.zeros(3, 1), ca.SX.zeros(3, 1), ca.SX.zeros(nm, 1)
    for i, (d, dv, da) in enumerate(paths):
        psi, dpsi, ddpsi = shapes[structure.carriages[i].root]
        m = masses[i]
        e = psi @ eta
        e_acc = psi @ accel + 2 * dpsi @ rate + ddpsi @ eta
        trans += m * e_acc
        rot += m * (ca.cross(d, e_acc) + ca.cross(e, da)) - ca.cross(m * e, g_world)
        absolute = acc_body + ca.cross(alpha_body, d) + 2 * ca.cross(w_body, dv) + da + e_acc - g_body
        modal += m * (psi.T @ absolute)
    return trans, rot, modal


def solve_mass(rigid: ca.SX, coupling: ca.SX, shapes: dict[int, tuple[ca.SX, ca.SX, ca.SX]],
               root_masses: dict[int, ca.SX], nm: int, rhs: ca.SX) -> ca.SX:
    """``M^-1 rhs`` for the mass matrix ``[[A, B], [B^T, I + U U^T]]`` by blocks, never forming the inverse:
    ``A`` (6, 6) the rigid block, ``B`` (6, modes) the coupling, ``U`` the columns ``sqrt(m_r) Psi_r^T`` of the
    carriages riding each root (Woodbury's identity for the modal block, whose inverse is applied to vectors in
    O(modes) operations, and a 6 x 6 Schur complement for the rest)."""
    if root_masses:
        u = ca.horzcat(*[ca.sqrt(root_masses[r]) * shapes[r][0].T for r in sorted(root_masses)])
        small = ca.SX.eye(u.shape[1]) + u.T @ u
        small_inv = ca.inv(small) if u.shape[1] <= 3 else ca.solve(small, ca.SX.eye(u.shape[1]))

        def modal_solve(v: ca.SX) -> ca.SX:
            return v - u @ (small_inv @ (u.T @ v))
    else:
        def modal_solve(v: ca.SX) -> ca.SX:
            return v

    d_inv_bt = modal_solve(coupling.T)  # (modes, 6)
    schur = rigid - coupling @ d_inv_bt
    rigid_part = solve_blocks(schur, rhs[:6] - coupling @ modal_solve(rhs[6:]))
    return ca.vertcat(rigid_part, modal_solve(rhs[6:] - coupling.T @ rigid_part))
