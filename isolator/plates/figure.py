"""The figure of a top's elastic mode shapes: filled contours of the vertical translation, one panel a mode."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public

__all__ = ["MAX_PANELS", "plot_mode_shapes"]

#: the most modes one figure shows
MAX_PANELS = 12
#: modes below this frequency are rigid and not drawn, Hz
_RIGID_HZ = 1.0
#: nodes within this of the highest node are the top face, m
_FACE = 1e-3


def plot_mode_shapes(nodes: np.ndarray, translations: np.ndarray, frequencies: np.ndarray, *,
                     isolators: np.ndarray | None = None, feet: np.ndarray | None = None,
                     title: str | None = None) -> Any:
    """The elastic mode shapes of a top: its vertical translation in filled contours over the top's outline.

    One panel per elastic mode (the lowest :data:`MAX_PANELS`; rigid modes, below 1 Hz, are skipped), each
    shape scaled by its largest translation in any direction (so one colour scale, -1 to 1, serves all, and
    a mode mostly in the plane stays pale: "(in-plane)" in its title and arrows of its in-plane
    translation when its vertical translation is less than half its largest), the frequency in its title.
    Modal data with two faces is drawn on its top face (nodes within 1 mm of the highest).

    Parameters
    ----------
    nodes : array_like
        Node positions (N, 3), m.
    translations : array_like
        Mode shapes' translations (n, N, 3) at the nodes, any scale.
    frequencies : array_like
        The modes' natural frequencies (n,), Hz.
    isolators : array_like, optional
        Isolator (x, y) positions (k, 2) or (k, 3) to mark, m.
    feet : array_like, optional
        Feet (x, y) positions (k, 2) or (k, 3) to mark, m.
    title : str, optional
        The figure's title (default "Elastic modes of the top").

    Returns
    -------
    matplotlib.figure.Figure
        The figure.

    Raises
    ------
    ParameterError
        Arrays of inconsistent shapes (named), or no elastic mode.
    """
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle
    from matplotlib.tri import Triangulation

    p = np.asarray(nodes, dtype=float)
    u = np.asarray(translations, dtype=float)
    f = np.asarray(frequencies, dtype=float).ravel()
    if p.ndim != 2 or p.shape[1] != 3:
        raise ParameterError(f"nodes: must be an (N, 3) array, got shape {p.shape}")
    if u.ndim != 3 or u.shape[1:] != p.shape:
        raise ParameterError(f"translations: must be an (n, {len(p)}, 3) array, got shape {u.shape}")
    if f.shape != (len(u),):
        raise ParameterError(f"frequencies: must hold {len(u)} values, got {f.size}")
    shown = np.flatnonzero(f >= _RIGID_HZ)[:MAX_PANELS]
    if not shown.size:
        raise ParameterError("frequencies: no elastic mode (every one below 1 Hz) to draw")
    face = p[:, 2] >= p[:, 2].max() - _FACE
    xy = p[face, :2]
    triangles = Triangulation(xy[:, 0], xy[:, 1])
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    columns = min(len(shown), 3 if len(shown) <= 9 else 4)
    rows = math.ceil(len(shown) / columns)
    aspect = (hi[1] - lo[1]) / max(hi[0] - lo[0], 1e-12)
    fig, axes = plt.subplots(rows, columns, figsize=(3.6 * columns + 1.2, (3.0 * aspect + 0.8) * rows + 1.0),
                             squeeze=False, sharex=True, sharey=True, layout="constrained")
    levels = np.linspace(-1.0, 1.0, 21)
    filled: Any = None
    for k, (ax, i) in enumerate(zip(axes.flat, shown, strict=False), start=1):
        largest = np.abs(u[i, face]).max()  # of any component: an in-plane mode stays pale
        w = u[i, face, 2] / largest if largest > 0 else u[i, face, 2]
        filled = ax.tricontourf(triangles, w, levels=levels, cmap="RdBu_r", extend="neither")
        in_plane = " (in-plane)" if np.abs(w).max() < 0.5 else ""
        if in_plane:  # its motion as arrows
            ax.quiver(xy[:, 0], xy[:, 1], u[i, face, 0], u[i, face, 1], color="0.25", width=0.004)
        ax.add_patch(Rectangle(lo, *(hi - lo), fill=False, edgecolor="k", linewidth=1.0))
        _mark(ax, isolators, "isolators", {"marker": "^", "color": "k", "mfc": "gold", "markersize": 9})
        _mark(ax, feet, "feet", {"marker": "X", "color": "k", "mfc": "limegreen", "markersize": 8})
        ax.set_title(f"elastic mode {k}: {f[i]:.4g} Hz{in_plane}", fontsize=10)
        ax.set_aspect("equal")
    for ax in axes.flat[len(shown):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("x [m]")
    for ax in axes[:, 0]:
        ax.set_ylabel("y [m]")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="outside lower center", ncols=len(handles), frameon=False)
    fig.colorbar(filled, ax=axes, shrink=0.8, label="vertical translation / largest translation",
                 ticks=[-1, -0.5, 0, 0.5, 1])
    fig.suptitle(title or "Elastic modes of the top")
    return fig


def _mark(ax: Any, where: Any, name: str, style: dict[str, Any]) -> None:
    """Mark (x, y) positions, if any, labelled ``name``."""
    if where is None:
        return
    xy = np.asarray(where, dtype=float).reshape(-1, np.shape(where)[-1] if np.ndim(where) > 1 else 2)
    if xy.shape[1] not in (2, 3):
        raise ParameterError(f"{name}: must be (x, y) or (x, y, z) positions, got shape {np.shape(where)}")
    ax.plot(xy[:, 0], xy[:, 1], label=name, linestyle="none", clip_on=False, zorder=5, **style)


check_public(globals())
