"""Motion of the scenario's ``[[points]]`` from the model's states: the world displacement of each point from
its position at the initial equilibrium (``<point>:x, :y, :z``, m; ``docs/scenario-format.md``).

A point's world position is the mass centre plus the table's rotation applied to the point's lever arm
(its position in the table frame, whose origin is the mass centre), with the exact rotation: the quaternion
(w, x, y, z) of the exact model's state, the Cardan angles ``Rz Ry Rx`` of the paper model's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from isolator.model.flexible.structure import point_shape
from isolator.scenario.definitions import Scenario

__all__ = ["PointSet", "elastic_translation", "point_positions", "rotation_matrices"]


def rotation_matrices(states: np.ndarray, kind: str) -> np.ndarray:
    """The table's rotation matrices (N, 3, 3) of states (N, n_states): ``kind`` "exact" (quaternion in
    ``states[:, 3:7]``, normalised) or "paper" (Cardan angles in ``states[:, 3:6]``)."""
    states = np.atleast_2d(np.asarray(states, dtype=float))
    if kind == "paper":
        cx, cy, cz = (np.cos(states[:, 3 + i]) for i in range(3))
        sx, sy, sz = (np.sin(states[:, 3 + i]) for i in range(3))
        rows = [[cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx],
                [sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx],
                [-sy, cy * sx, cy * cx]]
    else:
        q = states[:, 3:7] / np.linalg.norm(states[:, 3:7], axis=1, keepdims=True)
        w, x, y, z = q.T
        rows = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    return np.moveaxis(np.array(rows), 2, 0)


def elastic_translation(states: np.ndarray, shapes: np.ndarray) -> np.ndarray:
    """Elastic translations (points, 3, N), table frame [m], of points with ``shapes`` (points, 3, modes) at
    exact-model states (N, n_states) of a bending top (the modal coordinates after the first 13)."""
    nm = shapes.shape[2]
    return np.einsum("pim,nm->pin", shapes, np.atleast_2d(states)[:, 13:13 + nm])


def point_positions(states: np.ndarray, arms: np.ndarray, kind: str, shapes: np.ndarray | None = None
                    ) -> np.ndarray:
    """World positions (points, 3, N) [m] of table points with lever arms ``arms`` (points, 3; table frame,
    from the mass centre) at states (N, n_states) of the model ``kind`` ("exact" or "paper"); on a bending
    top with their elastic translation per modal coordinate ``shapes`` (points, 3, modes)."""
    states = np.atleast_2d(np.asarray(states, dtype=float))
    rot = rotation_matrices(states, kind)
    arms = np.asarray(arms, dtype=float).reshape(-1, 3)
    if shapes is None:
        turned = np.einsum("nij,pj->pin", rot, arms)
    else:  # the lever of each point at each state: its arm and its elastic translation
        turned = np.einsum("nij,pjn->pin", rot, arms[:, :, None] + elastic_translation(states, shapes))
    return turned + states[:, 0:3].T[None, :, :]


@dataclass(frozen=True)
class PointSet:
    """A run's points: names, lever arms, and the initial and settled positions they are measured from.

    Attributes
    ----------
    names : tuple of str
    arms : ndarray (points, 3)
        Positions in the table frame [m].
    kind : str
        The model ("exact" or "paper"), which says how the states hold the rotation.
    start : ndarray (points, 3)
        World positions at the initial equilibrium [m].
    settled : ndarray (points, 3) or None
        Displacement from ``start`` at the static equilibrium with the carriages at their final positions
        [m] (None when a carriage never stops).
    shapes : ndarray (points, 3, modes) or None
        On a bending top, each point's elastic translation per modal coordinate (table frame); the modal
        coordinates are the states after the rigid table's 13.
    rest : ndarray (points, 3) or None
        On a bending top, each point's elastic translation at the initial equilibrium from the undeformed
        top [m] (``deflection_at_rest``).
    """

    names: tuple[str, ...]
    arms: np.ndarray
    kind: str
    start: np.ndarray
    settled: np.ndarray | None
    shapes: np.ndarray | None = None
    rest: np.ndarray | None = None

    @classmethod
    def of(cls, scenario: Scenario, kind: str, start: np.ndarray, end: np.ndarray | None) -> PointSet:
        """The scenario's points for a run of model ``kind`` from the state ``start`` (final rest ``end``)."""
        arms = np.array([pt.position for pt in scenario.points], dtype=float).reshape(-1, 3)
        if not arms.size:  # no [[points]]: nothing to place (a run's hot path)
            return cls((), arms, kind, np.zeros((0, 3)), None if end is None else np.zeros((0, 3)))
        shapes = None
        if getattr(scenario.table, "flexible", None) is not None:
            shapes = np.array([point_shape(scenario.table, pt.position, getattr(pt, "feet", None),
                                           f"points ({pt.name})") for pt in scenario.points])
        first = point_positions(start, arms, kind, shapes)[:, :, 0]
        settled = None if end is None else point_positions(end, arms, kind, shapes)[:, :, 0] - first
        rest = None if shapes is None else elastic_translation(np.atleast_2d(start), shapes)[:, :, 0]
        return cls(tuple(pt.name for pt in scenario.points), arms, kind, first, settled, shapes, rest)

    def index(self, name: str) -> int:
        """The position of the point ``name``; a KeyError naming the known points."""
        if name not in self.names:
            raise KeyError(f"point: unknown '{name}' (points: {', '.join(self.names) or 'none'})")
        return self.names.index(name)

    def displacements(self, states: np.ndarray) -> np.ndarray:
        """Each point's displacement from its initial position (points, 3, N) [m] at states (N, n_states)."""
        return point_positions(states, self.arms, self.kind, self.shapes) - self.start[:, :, None]

    def elastic(self, states: np.ndarray) -> np.ndarray:
        """Each point's elastic translation from the initial equilibrium (points, 3, N), table axes [m]
        (``<point>:ex, :ey, :ez``; zeros on a rigid top)."""
        states = np.atleast_2d(np.asarray(states, dtype=float))
        if self.shapes is None or self.rest is None:
            return np.zeros((len(self.names), 3, states.shape[0]))
        return elastic_translation(states, self.shapes) - self.rest[:, :, None]

    def jacobian(self, state: np.ndarray) -> np.ndarray:
        """Each point's position's Jacobian (points, 3, n_states) at ``state`` [m per state unit], by central
        differences (steps of 1e-7 of each state's size: about 1e-9 relative)."""
        state = np.asarray(state, dtype=float)
        step = 1e-7 * np.maximum(1.0, np.abs(state))
        moved = np.vstack([state + np.diag(step), state - np.diag(step)])
        at = point_positions(moved, self.arms, self.kind, self.shapes)
        return (at[:, :, : state.size] - at[:, :, state.size :]) / (2 * step)

    @property
    def columns(self) -> tuple[str, ...]:
        """The CSV/signal names ``<point>:x, <point>:y, <point>:z`` per point."""
        return tuple(f"{n}:{a}" for n in self.names for a in "xyz")

    @property
    def elastic_columns(self) -> tuple[str, ...]:
        """``<point>:ex, :ey, :ez`` per point on a bending top (none on a rigid one)."""
        return () if self.shapes is None else tuple(f"{n}:e{a}" for n in self.names for a in "xyz")
