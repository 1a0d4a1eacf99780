"""Static equilibrium of the parked table, its stability and its rocking-stiffness margin."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import UnstableTableError
from .model import Model, build_linearisation

__all__ = ["DOF_NAMES", "Equilibrium", "RockingStiffness", "rocking_stiffness", "static_equilibrium"]

DOF_NAMES = ("x", "y", "z", "rx", "ry", "rz")


@dataclass(frozen=True)
class Equilibrium:
    """The table at rest under the carriages parked at ``positions``.

    Attributes
    ----------
    pose : ndarray (6,)
        Mass-centre position from the reference pose [m] and Cardan angles
        (Rz Ry Rx) [rad].
    state : ndarray
        The model's state at rest in that pose.
    positions : ndarray
        Carriage coordinates [m].
    eigenvalues : ndarray
        Of the model linearised there [1/s].
    """

    pose: np.ndarray
    state: np.ndarray
    positions: np.ndarray
    eigenvalues: np.ndarray

    @property
    def max_frequency(self) -> float:
        """Largest eigenvalue modulus [rad/s]."""
        return float(np.max(np.abs(self.eigenvalues), initial=0.0))


@dataclass(frozen=True)
class RockingStiffness:
    """The table's static stiffness against rotation, translations free to follow.

    The stiffness matrix about the rest pose is condensed onto the three
    rotations (the translations take their static values), giving a 3x3
    rocking stiffness whose eigenvalues must all be positive for the table to
    stand. The weight above the isolators' attachment points takes part of the
    isolators' own rocking stiffness away (about ``W h``).

    Attributes
    ----------
    values : ndarray (3,)
        Eigenvalues of the condensed rocking stiffness, ascending [N m/rad].
    directions : ndarray (3, 3)
        Their unit rotation axes (columns), world frame.
    elastic : ndarray (3,)
        The isolators' part along those axes, without gravity [N m/rad].
    """

    values: np.ndarray
    directions: np.ndarray
    elastic: np.ndarray

    @property
    def margin(self) -> float:
        """Smallest rocking stiffness [N m/rad]; <= 0: the table tips."""
        return float(self.values[0])

    @property
    def relative_margin(self) -> float:
        """``margin`` as a fraction of the isolators' own rocking stiffness along that axis."""
        return float(self.values[0] / self.elastic[0]) if self.elastic[0] > 0 else float("-inf")

    @property
    def weakest_axis(self) -> str:
        """``rx``, ``ry`` or ``rz``: the world axis closest to the softest rotation."""
        return DOF_NAMES[3 + int(np.argmax(np.abs(self.directions[:, 0])))]

    @property
    def stable(self) -> bool:
        return self.margin > 0.0

    def describe(self) -> str:
        """One line for reports and error messages."""
        taken = self.elastic[0] - self.values[0]
        return (
            f"rocking stiffness about {self.weakest_axis} = {self.margin:.4g} N m/rad "
            f"({100 * self.relative_margin:.3g} % of the isolators' {self.elastic[0]:.4g}; "
            f"the weight above their attachment points takes {taken:.4g})"
        )


def rocking_stiffness(model: Model, p: np.ndarray, positions: np.ndarray, pose: np.ndarray) -> RockingStiffness:
    """Condensed rocking stiffness of the exact model at a rest ``pose`` (position [m], Cardan angles [rad]).

    Parameters
    ----------
    model : Model
        Any model of the scenario's structure (the exact equations are used).
    p : ndarray
        Parameter vector.
    positions : ndarray
        Carriage coordinates [m].
    pose : ndarray (6,)
        Usually the static equilibrium's.
    """
    lin = build_linearisation(model.layout)
    c = np.concatenate([np.asarray(positions, float), np.zeros(2 * len(positions))])

    def condensed(params: np.ndarray) -> np.ndarray:
        k = np.asarray(lin(pose, c, params)[2], dtype=float)
        k = 0.5 * (k + k.T)
        return k[3:, 3:] - k[3:, :3] @ np.linalg.pinv(k[:3, :3]) @ k[:3, 3:]

    values, vectors = np.linalg.eigh(condensed(p))
    no_gravity = np.array(p, dtype=float)
    no_gravity[0] = 0.0
    elastic_matrix = condensed(no_gravity)
    elastic = np.einsum("ik,ij,jk->k", vectors, elastic_matrix, vectors)
    return RockingStiffness(values, vectors, elastic)


def static_equilibrium(
    model: Model, p: np.ndarray, positions: np.ndarray, where: str = "at rest", check: bool = True
) -> Equilibrium:
    """Solve for the table's static pose and check that it is stable.

    Parameters
    ----------
    model : Model
    p : ndarray
        Parameter vector.
    positions : ndarray
        Carriage coordinates [m].
    where : str
        Words for messages, e.g. "with the carriages at their start".
    check : bool
        Raise when the equilibrium is unstable (False: return it anyway).

    Raises
    ------
    UnstableTableError
        No equilibrium, or one with a divergent mode (the table would tip);
        the message gives the rocking-stiffness margin.
    """
    c = model.layout.rest_inputs(positions)
    z = np.zeros(6)
    weight = abs(float(p[0])) * float(p[1]) + 1.0
    converged = False
    for _ in range(40):
        r, jac = model.static_residual(z, c, p)
        r = np.asarray(r, dtype=float).ravel()
        if not np.all(np.isfinite(r)):
            break
        if np.max(np.abs(r)) <= 1e-11 * weight:
            converged = True
            break
        dz = np.linalg.lstsq(np.asarray(jac, dtype=float), -r, rcond=None)[0]
        z = z + dz
        if np.max(np.abs(dz)) < 1e-15:
            converged = True
            break
        if np.max(np.abs(z[3:])) > 1.0:
            break
    if not converged:
        rock = rocking_stiffness(model, p, positions, np.zeros(6))
        raise UnstableTableError(
            f"no static equilibrium {where}: the isolators cannot hold the table upright; "
            f"{rock.describe()} (the mass centre is too high for the isolator spacing, or they are too soft)"
        )
    state = np.asarray(model.pose_state(z), dtype=float).ravel()
    a = np.asarray(model.state_jacobian(state, c, p), dtype=float)
    eig, vec = np.linalg.eig(a)
    scale = float(np.max(np.abs(eig), initial=0.0))
    worst = int(np.argmax(eig.real))
    if check and eig.real[worst] > 1e-9 * scale + 1e-9:
        dof = _dominant_dof(model, vec[:, worst])
        rock = rocking_stiffness(model, p, positions, z)
        raise UnstableTableError(
            f"unstable table {where}: a mode mostly in {dof} grows at {eig.real[worst]:.3g} 1/s; "
            f"{rock.describe()}; the mass centre is too high for the isolator spacing "
            "(or an isolator is too soft) and the table would tip"
        )
    return Equilibrium(z, state, np.asarray(positions, float), eig)


def _dominant_dof(model: Model, vector: np.ndarray) -> str:
    v = np.abs(vector)
    motion = np.concatenate([v[0:3], 2 * v[4:7]]) if model.kind == "exact" else v[0:6]
    return DOF_NAMES[int(np.argmax(motion))]
