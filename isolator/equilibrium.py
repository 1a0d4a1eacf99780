"""Static equilibrium of the parked table and its stability."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import UnstableTableError
from .model import Model

__all__ = ["DOF_NAMES", "Equilibrium", "static_equilibrium"]

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


def static_equilibrium(
    model: Model, p: np.ndarray, positions: np.ndarray, where: str = "at rest"
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

    Raises
    ------
    UnstableTableError
        No equilibrium, or one with a divergent mode (the table would tip).
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
        raise UnstableTableError(
            f"no static equilibrium {where}: the isolators cannot hold the table "
            "(too soft, or the mass centre too high for their spacing)"
        )
    state = np.asarray(model.pose_state(z), dtype=float).ravel()
    a = np.asarray(model.state_jacobian(state, c, p), dtype=float)
    eig, vec = np.linalg.eig(a)
    scale = float(np.max(np.abs(eig), initial=0.0))
    worst = int(np.argmax(eig.real))
    if eig.real[worst] > 1e-9 * scale + 1e-9:
        dof = _dominant_dof(model, vec[:, worst])
        raise UnstableTableError(
            f"unstable table {where}: a mode mostly in {dof} grows at "
            f"{eig.real[worst]:.3g} 1/s; the mass centre is too high for the isolator "
            "spacing (or an isolator is too soft) and the table would tip"
        )
    return Equilibrium(z, state, np.asarray(positions, float), eig)


def _dominant_dof(model: Model, vector: np.ndarray) -> str:
    v = np.abs(vector)
    motion = np.concatenate([v[0:3], 2 * v[4:7]]) if model.kind == "exact" else v[0:6]
    return DOF_NAMES[int(np.argmax(motion))]
