"""The wrenches of the feedforward: the carriages' inertial reaction and the actuators' allocation.

Forces [N] and moments [N m] about the table's mass centre, world axes (or
the table's, where said).
"""

from __future__ import annotations

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario

__all__ = ["allocation_matrix", "carriage_inertia_wrench", "reaction_wrench"]


def allocation_matrix(scenario: Scenario, rot: np.ndarray) -> np.ndarray:
    """Wrench per unit actuator force, shape (..., 6, n_actuators).

    Rows: force [N] and moment about the table's mass centre [N m], world axes,
    with the table turned by ``rot`` (..., 3, 3) (table to world).

    Parameters
    ----------
    scenario : Scenario
        The scenario, with ``[[actuators]]`` (or a bundled scenario's name, or a TOML file's path).
    rot : ndarray
        (..., 3, 3): the table's orientation, table to world.

    Returns
    -------
    ndarray
        (..., 6, n_actuators): force [N] and moment [N m] at the table's mass centre per newton of each
        actuator's force.
    """
    d = np.array([a.direction for a in scenario.actuators], dtype=float)  # (n, 3)
    p = np.array([a.position for a in scenario.actuators], dtype=float)
    arms = np.einsum("...ij,nj->...ni", rot, p)
    moments = np.cross(arms, d)
    force = np.broadcast_to(d, moments.shape)
    return np.swapaxes(np.concatenate([force, moments], axis=-1), -1, -2)


def reaction_wrench(scenario: Scenario, t: np.ndarray, piece_time: np.ndarray | None, rot: np.ndarray) -> np.ndarray:
    """The wrench that cancels the carriages' inertial reaction, (N, 6) [N, N m], world axes.

    ``sum m_i a_i`` and ``sum m_i d_i x a_i`` with ``d_i`` the carriage masses'
    positions and ``a_i`` their accelerations relative to the table, about its
    mass centre, turned by the table's orientation ``rot`` (N, 3, 3).

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).
    t : ndarray
        (N,): times [s].
    piece_time : ndarray or None
        (N,): times that pick each profile's piece (one-sided at breakpoints); None: ``t``.
    rot : ndarray
        (N, 3, 3): the table's orientation, table to world.

    Returns
    -------
    ndarray
        (N, 6): force [N] and moment [N m] in world axes.
    """
    t, rot = np.asarray(t, dtype=float), np.asarray(rot, dtype=float)
    if t.ndim != 1:
        raise ParameterError(f"t: must be a 1-D array of times [s], got shape {t.shape}")
    if rot.shape != (t.size, 3, 3):
        raise ParameterError(f"rot: must be one rotation matrix per time, shape ({t.size}, 3, 3), got {rot.shape}")
    if piece_time is not None and np.shape(piece_time) != t.shape:
        raise ParameterError(f"piece_time: must be one time per t, shape {t.shape}, got {np.shape(piece_time)}")
    n = len(scenario.carriages)
    q = np.zeros((n, t.size))
    qdd = np.zeros((n, t.size))
    for i, c in enumerate(scenario.carriages):
        q[i], _, qdd[i] = c.profile.evaluate(t, piece_time)
    wrench = carriage_inertia_wrench(scenario, q, qdd)
    return np.hstack([np.einsum("nij,nj->ni", rot, wrench[:, :3]), np.einsum("nij,nj->ni", rot, wrench[:, 3:])])


def carriage_inertia_wrench(scenario: Scenario, q: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """``sum m_i a_i`` and ``sum m_i d_i x a_i`` in the table's axes, (N, 6) [N, N m].

    ``d_i`` are the carriage masses' positions about the table's mass centre
    at coordinates ``q`` (n, N) and ``a_i`` their accelerations relative to the
    table for coordinate accelerations ``qdd`` (n, N); a carriage's
    acceleration carries the carriages riding on it.

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).
    q : ndarray
        (n_carriages, N): the carriages' coordinates [m].
    qdd : ndarray
        (n_carriages, N): their coordinate accelerations [m/s^2].

    Returns
    -------
    ndarray
        (N, 6): the force [N] and moment [N m] in the table's axes.
    """
    pos = scenario.carriage_positions(q)  # (n, 3, N)
    acc = scenario.carriage_positions(qdd) - scenario.carriage_positions(np.zeros_like(qdd))
    m = np.array([c.mass for c in scenario.carriages])[:, None, None]
    force = np.sum(m * acc, axis=0).T
    moment = np.sum(m * np.cross(pos, acc, axis=1), axis=0).T
    return np.hstack([force, moment])


check_public(globals())
