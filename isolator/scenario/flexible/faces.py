"""The faces of a bending top: which nodes form its top and bottom face, and each face's C1 interpolant.

A face's nodes are those within :data:`TOLERANCE` (1 mm) of the highest (top) or lowest (bottom) node ``z``;
a file whose nodes all lie within it of one height is a single layer (a shell's mid-surface), whose faces
are that layer moved by half the thickness: ``u + theta x (0, 0, +-t/2)``. Each face's translations are
interpolated over its nodes' ``(x, y)`` with scipy's Clough-Tocher interpolant (a C1 piecewise cubic on
the Delaunay triangulation), defined on the nodes' convex hull; a point within 1 mm outside it is taken
at the nearest point of the hull, a point farther out is an error naming it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.interpolate import CloughTocher2DInterpolator
from scipy.spatial import Delaunay, QhullError

from isolator.errors import ScenarioError

__all__ = ["FACES", "TOLERANCE", "FaceInterpolant", "face_nodes", "face_values", "is_single_layer"]

#: how far from a face's height its nodes, and outside its outline a point, may lie [m]
TOLERANCE = 1e-3
#: the faces of the top, as ``face_for`` names them
FACES = ("top", "bottom")
#: the relative tolerance of the interpolant's gradient estimate (scipy's default 1e-6 leaves errors of some 1e-6
#: even in a linear field; this one reproduces it to rounding at about twice the cost)
GRADIENT_TOLERANCE = 1e-12
#: the decimals [m] the nodes' (x, y) are rounded to before they are triangulated
_ROUND = 9


def is_single_layer(nodes: np.ndarray) -> bool:
    """Whether every node lies within :data:`TOLERANCE` of one height (a shell's mid-surface)."""
    z = np.asarray(nodes, dtype=float)[:, 2]
    return bool(z.max() - z.min() <= TOLERANCE)


def face_nodes(nodes: np.ndarray, face: str) -> np.ndarray:
    """The indices of a face's nodes: within 1 mm of the highest (``top``) or lowest (``bottom``) ``z``."""
    z = np.asarray(nodes, dtype=float)[:, 2]
    if is_single_layer(nodes):
        return np.arange(z.size)
    return np.flatnonzero(z >= z.max() - TOLERANCE if face == "top" else z <= z.min() + TOLERANCE)


def face_values(translations: np.ndarray, rotations: np.ndarray | None, nodes: np.ndarray, thickness: float,
                face: str) -> np.ndarray:
    """Each mode's translation of the face's nodes, (face nodes, modes, 3): the nodes' own on a solid's
    face, ``u + theta x (0, 0, +-t/2)`` on a single layer (``+`` the top face) [m/sqrt(kg)]."""
    index = face_nodes(nodes, face)
    u = np.array(translations[:, index, :], dtype=float)
    if is_single_layer(nodes) and rotations is not None:
        half = (thickness if face == "top" else -thickness) / 2.0
        theta = rotations[:, index, :]
        u[..., 0] += theta[..., 1] * half  # theta x (0, 0, h) = (theta_y h, -theta_x h, 0)
        u[..., 1] -= theta[..., 0] * half
    return np.moveaxis(u, 1, 0)


def check_face(nodes: np.ndarray, face: str, where: str, labels: Sequence[str] = ()) -> None:
    """A face fit for interpolation: three or more nodes, not all on one line, no two at one ``(x, y)``;
    else a :class:`ScenarioError` starting with ``where`` and naming the nodes (``labels``: each node's name,
    default ``node i``)."""
    index = face_nodes(nodes, face)
    name = (lambda i: labels[i]) if labels else (lambda i: f"node {i + 1}")
    z = nodes[:, 2]
    side = "highest" if face == "top" else "lowest"
    height = z.max() if face == "top" else z.min()
    if index.size < 3:
        shown = ", ".join(name(int(i)) for i in index)
        raise ScenarioError(f"{where}: the {face} face (nodes within 1 mm of the {side} z = {height:.6g} m) has "
                            f"{index.size} node{'s' if index.size != 1 else ''} ({shown}); a face needs at least 3 "
                            "(a solid's top and bottom faces, or a single layer of nodes with rotations)")
    xy = nodes[index, :2]
    spread = np.linalg.svd(xy - xy.mean(axis=0), compute_uv=False)
    if spread[1] <= 1e-9 * max(spread[0], 1e-300):
        raise ScenarioError(f"{where}: the {face} face's {index.size} nodes ({name(int(index[0]))} ...) lie on one "
                            "line in (x, y); the face's shape cannot be interpolated over the top")
    order = np.lexsort((xy[:, 1], xy[:, 0]))
    step = np.abs(np.diff(xy[order], axis=0)).max(axis=1)
    scale = max(float(np.abs(xy).max()), 1.0)
    same = np.flatnonzero(step <= 1e-9 * scale)
    if same.size:
        a, b = int(index[order[same[0]]]), int(index[order[same[0] + 1]])
        raise ScenarioError(f"{where}: {name(a)} and {name(b)} of the {face} face lie at the same (x, y) = "
                            f"({xy[order[same[0]], 0]:.6g}, {xy[order[same[0]], 1]:.6g}) m; a face has one node "
                            "per point of its outline")


class FaceInterpolant:
    """One face's translations interpolated over its nodes' ``(x, y)`` (Clough-Tocher, C1 cubic).

    Parameters
    ----------
    xy : ndarray, shape (k, 2)
        The face's nodes [m].
    values : ndarray, shape (k, ...)
        Their values (each mode's translation components).
    """

    def __init__(self, xy: np.ndarray, values: np.ndarray) -> None:
        # a structured mesh's cells have four nodes on a circle, whose Delaunay diagonal rounding decides: nodes
        # rounded to 1 nm triangulate alike whichever file (CSV or UFF) or origin they came through
        xy = np.round(np.asarray(xy, dtype=float), _ROUND)
        try:
            self._tri = Delaunay(xy)
        except (QhullError, ValueError) as exc:  # check_face refuses what Qhull cannot triangulate
            raise ScenarioError(f"the face's nodes cannot be triangulated ({' '.join(str(exc).split())[:80]})"
                                ) from None
        self._values = values
        self._interpolant: CloughTocher2DInterpolator | None = None  # built when first evaluated
        edges = self._tri.convex_hull
        self._start = self._tri.points[edges[:, 0]]
        self._end = self._tri.points[edges[:, 1]]
        self._centre = self._tri.points.mean(axis=0)

    def nearest(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The nearest point of the face's outline (convex hull) to each point, and the distance (0 inside) [m]."""
        p = np.asarray(points, dtype=float).reshape(-1, 2)
        inside = self._tri.find_simplex(p) >= 0
        dist = np.zeros(len(p))
        out = p.copy()
        if not inside.all():
            q = p[~inside, None, :]
            edge = self._end - self._start
            t = np.clip(np.sum((q - self._start) * edge, axis=-1) / np.sum(edge * edge, axis=-1), 0.0, 1.0)
            foot = self._start + t[..., None] * edge
            gap = np.linalg.norm(q - foot, axis=-1)
            k = np.argmin(gap, axis=1)
            rows = np.arange(len(k))
            dist[~inside] = gap[rows, k]
            out[~inside] = foot[rows, k] + 1e-9 * (self._centre - foot[rows, k])  # just inside the hull
        return out, dist

    def __call__(self, points: np.ndarray) -> np.ndarray:
        """The interpolated values at ``points`` (k, 2), those just outside taken at the outline: (k, ...)."""
        inner, _ = self.nearest(points)
        if self._interpolant is None:
            self._interpolant = CloughTocher2DInterpolator(self._tri, self._values, tol=GRADIENT_TOLERANCE,
                                                           maxiter=10000)
        return np.asarray(self._interpolant(inner), dtype=float)
