"""The top's mass, mass centre and inertia from the six rigid modes of a free-free modal file, and their check
against ``[table]``.

Each rigid mode is fitted as ``u = v + w x p`` over the nodes (least squares on the translations, and on the
rotations ``theta = w`` when the file gives them). With the rigid coordinates ``(V, W)`` of the file's
origin, the kinetic energy ``m |V + W x c|^2 / 2 + W^T I W / 2`` has the mass matrix ``M`` whose inverse the
mass-normalised modes give (``A^T M A = I6`` with ``A = [v; w]``, so ``M^-1 = A A^T``):

    sum w w^T = I^-1,   sum v w^T = [c]x I^-1,   sum v' v'^T = I3 / m  with  v' = v + w x c,

``[c]x`` the cross-product matrix of the mass centre ``c``; ``v'`` is the mode's translation of the mass
centre, where the translation and rotation decouple.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from isolator.errors import ScenarioError

__all__ = ["MASS_TOLERANCE", "RIGID_LIMIT", "RigidCheck", "check_rigid", "fit_rigid", "rigid_properties"]

#: modes below this frequency are the top's rigid motions [Hz]
RIGID_LIMIT = 1.0
#: how far the rigid modes' mass may be from ``[table] mass``, and their mass centre from the table frame's
#: origin in the top's largest size (fractions)
MASS_TOLERANCE = 0.01
#: the largest relative residual of a rigid mode's fit ``u = v + w x p``: beyond it the mode is no rigid motion
FIT_TOLERANCE = 0.02


@dataclass(frozen=True, eq=False)
class RigidCheck:
    """What the six rigid modes of a modal file say of the top (arrays read-only).

    Attributes
    ----------
    mass : float
        [kg]
    centre : ndarray, shape (3,)
        The mass centre in the table frame [m].
    inertia : ndarray, shape (3, 3)
        The inertia tensor about the mass centre, table axes [kg m^2].
    """

    mass: float
    centre: np.ndarray
    inertia: np.ndarray


def fit_rigid(nodes: np.ndarray, translations: np.ndarray, rotations: np.ndarray | None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each mode fitted as a rigid motion ``u = v + w x p`` over the nodes, least squares.

    Parameters
    ----------
    nodes : ndarray, shape (N, 3)
        [m]
    translations : ndarray, shape (r, N, 3)
        [m/sqrt(kg)]
    rotations : ndarray, shape (r, N, 3), optional
        [rad/sqrt(kg)], fitted as ``theta = w`` (weighted by the nodes' extent, so both in metres).

    Returns
    -------
    v, w : ndarray, shape (r, 3)
        The translation of the origin [m/sqrt(kg)] and the rotation [rad/sqrt(kg)].
    residual : ndarray, shape (r,)
        The translations' residual over their norm.
    """
    p = np.asarray(nodes, dtype=float)
    n = len(p)
    rows = np.zeros((n, 3, 6))
    rows[:, :, :3] = np.eye(3)
    rows[:, 0, 4], rows[:, 0, 5] = p[:, 2], -p[:, 1]  # w x p = (wy pz - wz py, wz px - wx pz, wx py - wy px)
    rows[:, 1, 3], rows[:, 1, 5] = -p[:, 2], p[:, 0]
    rows[:, 2, 3], rows[:, 2, 4] = p[:, 1], -p[:, 0]
    matrix = rows.reshape(3 * n, 6)
    right = translations.reshape(len(translations), 3 * n).T
    if rotations is not None:
        scale = max(float(np.ptp(p, axis=0).max()), 1e-3)
        spin = np.zeros((n, 3, 6))
        spin[:, :, 3:] = scale * np.eye(3)
        matrix = np.vstack([matrix, spin.reshape(3 * n, 6)])
        right = np.vstack([right, scale * rotations.reshape(len(rotations), 3 * n).T])
    solution = np.linalg.lstsq(matrix, right, rcond=None)[0]
    fitted = rows.reshape(3 * n, 6) @ solution
    own = translations.reshape(len(translations), 3 * n).T
    residual = np.linalg.norm(fitted - own, axis=0) / np.maximum(np.linalg.norm(own, axis=0), 1e-300)
    return solution[:3].T, solution[3:].T, residual


def rigid_properties(v: np.ndarray, w: np.ndarray) -> RigidCheck:
    """The mass, mass centre and inertia of a body whose six mass-normalised rigid modes are ``u = v + w x p``.

    Parameters
    ----------
    v, w : ndarray, shape (6, 3)
        Each mode's translation of the frame's origin [m/sqrt(kg)] and rotation [rad/sqrt(kg)].

    Returns
    -------
    RigidCheck

    Raises
    ------
    ScenarioError
        When the six modes are not independent rigid motions (their inverse inertia or mass singular).
    """
    inverse_inertia = w.T @ w
    coupling = v.T @ w
    try:
        inertia = np.linalg.inv(inverse_inertia)
        skew = coupling @ inertia
    except np.linalg.LinAlgError:
        raise ScenarioError("the six rigid modes do not span three rotations") from None
    centre = 0.5 * np.array([skew[2, 1] - skew[1, 2], skew[0, 2] - skew[2, 0], skew[1, 0] - skew[0, 1]])
    moved = v + np.cross(w, centre)
    trace = float(np.trace(moved.T @ moved))
    if not (math.isfinite(trace) and trace > 0):
        raise ScenarioError("the six rigid modes do not span three translations")
    inertia = 0.5 * (inertia + inertia.T)
    for array in (centre, inertia):
        array.setflags(write=False)
    return RigidCheck(mass=3.0 / trace, centre=centre, inertia=inertia)


def _mass_cause(ratio: float) -> str:
    """The likely cause of a rigid-mode mass ``ratio`` times the table's."""
    causes = ((-6.0, "lengths in mm (shapes in mm/sqrt(kg))"), (-3.0, "masses in tonnes (shapes per sqrt(t))"),
              (-9.0, "lengths in mm and masses in tonnes"), (3.0, "masses in grams"))
    decades = math.log10(ratio) if ratio > 0 else 0.0
    for at, cause in causes:
        if abs(decades - at) < 0.3:
            return f"a file with {cause}?"
    return "shapes not mass-normalised (phi^T M phi = 1), or a model of another top?"


def check_rigid(rigid: RigidCheck, mass: float, largest: float, where: str,
                origin: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
    """The rigid modes' top against ``[table]``: its mass within 1 % of ``mass``, its mass centre within 1 % of
    the top's ``largest`` size [m] from the table frame's origin; else one :class:`ScenarioError` starting with
    ``where`` and naming both values and the likely cause (``origin``: the file's, for the hint)."""
    if abs(rigid.mass - mass) > MASS_TOLERANCE * mass:
        ratio = rigid.mass / mass
        raise ScenarioError(f"{where}: its six rigid modes give a top of mass {rigid.mass:.4g} kg, [table] mass is "
                            f"{mass:.4g} kg ({ratio:.3g} times; within 1 % needed): {_mass_cause(ratio)}")
    off = float(np.linalg.norm(rigid.centre))
    if off > MASS_TOLERANCE * largest:
        tiny = 1e-9 * max(largest, 1.0)  # rounding noise of the fit shown as 0
        c = ", ".join(f"{x if abs(x) > tiny else 0.0:.4g}" for x in rigid.centre)
        moved = ", ".join(f"{o - x if abs(o - x) > tiny else 0.0:.4g}" for o, x in zip(origin, rigid.centre,
                                                                                          strict=True))
        raise ScenarioError(f"{where}: its six rigid modes put the top's mass centre at [{c}] m in the table frame, "
                            f"{off:.4g} m from the table frame's origin (its mass centre; within 1 % of the top's "
                            f"largest size {largest:.4g} m = {MASS_TOLERANCE * largest:.3g} m needed): a file about "
                            f"another origin? (table.flexible.origin = [{moved}] puts the centres together)")
