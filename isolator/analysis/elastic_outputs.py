"""Outputs of the linear model at table points, with a bending top's elastic translation.

A point fixed to the table at ``p`` (table frame) moves by the table's rigid motion at ``p`` plus the
elastic translation there, the mean over its feet of the face translation ``sum_i phi_i eta_i``
(``docs/scenario-format.md``, "A top that bends").
"""

from __future__ import annotations

from typing import Any

import numpy as np

from isolator.analysis.sensor_outputs import skew_matrix
from isolator.model.flexible.structure import point_shape
from isolator.model.rotations import pose_rotation
from isolator.scenario.definitions import Scenario, Table

__all__ = ["point_force_weights", "point_rows", "sensor_shapes"]


def point_rows(point: Any, rot0: np.ndarray, ndof: int, table: Table) -> np.ndarray:
    """Output rows of a point over the states ``(d, d')`` (``ndof`` each): its world displacement ``x, y, z``
    [m], then on a bending top its elastic translation ``ex, ey, ez`` (table axes) [m]."""
    arm = rot0 @ np.asarray(point.position, dtype=float)
    shape = point_shape(table, point.position, getattr(point, "feet", None), f"points ({point.name})")
    rows = np.zeros((3 if shape is None else 6, 2 * ndof))
    rows[:3, :3], rows[:3, 3:6] = np.eye(3), -skew_matrix(arm)
    if shape is not None:
        rows[:3, 6:ndof] = rot0 @ shape
        rows[3:, 6:ndof] = shape
    return rows


def sensor_shapes(scenario: Scenario) -> list[np.ndarray | None]:
    """Each sensor's elastic translation per unit modal coordinate (3, modes) on a bending top (None for a
    floor sensor or a rigid top)."""
    if getattr(scenario.table, "flexible", None) is None:
        return [None] * len(scenario.sensors)
    return [None if s.on == "floor" else point_shape(scenario.table, s.position, None, f"sensors ({s.name})")
            for s in scenario.sensors]


def point_force_weights(lin: Any, position: Any, direction: Any, feet: Any = None, what: str = "point"
                        ) -> np.ndarray:
    """A force along the world ``direction`` at a table point as weights on the linear model's inputs: the
    force and its moment about the mass centre (``force:x .. torque:z``) and, on a bending top, its
    generalised forces on the modes (``modal:eta1 ..``) through the point's elastic translation.

    Parameters
    ----------
    lin : LinearModel
    position : array-like (3,)
        The point in the table frame [m].
    direction : array-like (3,)
        The force's direction, world axes (its length is the force per unit input).
    feet : tuple of (x, y), optional
        The point's feet on the top (their mean translation).
    what : str
        The point, for errors.

    Returns
    -------
    ndarray (inputs,)
    """
    names = list(lin.input_names)
    rot0 = pose_rotation(lin.equilibrium.pose[3:6])
    direction = np.asarray(direction, dtype=float)
    arm = rot0 @ np.asarray(position, dtype=float)
    weights = np.zeros(len(names))
    first = names.index("force:x")
    weights[first:first + 3] = direction
    weights[first + 3:first + 6] = np.cross(arm, direction)
    shape = point_shape(lin.scenario.table, position, feet, what)
    if shape is not None:
        modal = shape.T @ (rot0.T @ direction)
        first_modal = names.index("modal:eta1")
        weights[first_modal:first_modal + modal.size] = modal
    return weights
