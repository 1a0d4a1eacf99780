"""Names of a top's elastic modes by their motion: ``twist 1``, ``bending x 1``, ``bending y 2``, ``plate 3``.

A free-free mode of a rectangular top is named from its vertical translation ``w`` over the top face: a
twist is odd in both ``x`` and ``y`` (``w`` correlates with ``x y``), a bending along ``x`` varies along
``x`` and hardly along ``y`` (and so for ``y``), a mode moving mostly in the plane of the top is
``in-plane``, anything else ``plate``; each family is counted from 1 in ascending frequency.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["elastic_mode_names"]

#: the share of ``w``'s variance a family's pattern must hold to name the mode after it
_SHARE = 0.6


def _face_samples(data: Any, count: int = 25) -> tuple[np.ndarray, np.ndarray]:
    """Points of the top face on a grid over the nodes' extent, and the modes' translations there (k, n, 3)."""
    xy_nodes = np.asarray(data.nodes, dtype=float)[:, :2]
    lo, hi = xy_nodes.min(axis=0), xy_nodes.max(axis=0)
    gx, gy = np.meshgrid(np.linspace(lo[0], hi[0], count), np.linspace(lo[1], hi[1], count), indexing="ij")
    xy = np.column_stack([gx.ravel(), gy.ravel()])
    face = data.face_for(float(np.max(np.asarray(data.nodes)[:, 2])) + 1.0)
    xy = xy[np.asarray(data.inside(xy, face), dtype=bool)]
    return xy, np.asarray(data.translation(xy, face, "the modes' names"), dtype=float)


def _family(xy: np.ndarray, u: np.ndarray) -> str:
    """The family of one mode from its translations ``u`` (k, 3) at points ``xy`` (k, 2)."""
    w = u[:, 2]
    if np.sum(u[:, :2] ** 2) > np.sum(w**2):
        return "in-plane"
    centre = 0.5 * (xy.min(axis=0) + xy.max(axis=0))
    half = np.maximum(0.5 * (xy.max(axis=0) - xy.min(axis=0)), 1e-12)
    x, y = ((xy - centre) / half).T
    w = w - w.mean()
    total = float(np.sum(w**2))
    if total <= 0.0:
        return "plate"
    twist = float(np.dot(w, x * y)) ** 2 / float(np.dot(x * y, x * y)) / total
    if twist >= _SHARE:
        return "twist"
    # the share of w explained by a function of x alone (its mean over each column of the grid), and of y
    along_x = _explained(x, w) / total
    along_y = _explained(y, w) / total
    if along_x >= _SHARE and along_x > along_y:
        return "bending x"
    if along_y >= _SHARE:
        return "bending y"
    return "plate"


def _explained(coord: np.ndarray, w: np.ndarray) -> float:
    """The variance of ``w`` held by its mean over equal values of ``coord`` (a function of that coordinate)."""
    keys = np.round(coord, 6)
    out = 0.0
    for key in np.unique(keys):
        sel = keys == key
        out += float(sel.sum()) * float(np.mean(w[sel])) ** 2
    return out


def elastic_mode_names(data: Any) -> tuple[str, ...]:
    """The kept elastic modes' names, in the file's order (ascending frequency).

    Parameters
    ----------
    data : ModalData
        The modes (``frequencies``, ``nodes``, ``face_for``, ``inside``, ``translation``).

    Returns
    -------
    tuple of str
        ``twist 1``, ``bending x 1``, ... per mode.
    """
    xy, shapes = _face_samples(data)
    counts: dict[str, int] = {}
    names = []
    for k in range(shapes.shape[1]):
        family = _family(xy, shapes[:, k, :])
        counts[family] = counts.get(family, 0) + 1
        names.append(f"{family} {counts[family]}")
    return tuple(names)
