"""The panel of a run's figure that shows a bending top: each point's elastic translation over time."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["plot_elastic"]


def plot_elastic(ax: Any, t: np.ndarray, names: Sequence[str], elastic: np.ndarray, stop_time: float) -> None:
    """Draw each point's elastic translation ``ex, ey, ez`` from the initial equilibrium [um] against time.

    Parameters
    ----------
    ax : matplotlib Axes
    t : ndarray (N,)
        [s].
    names : sequence of str
        The points.
    elastic : ndarray (points, 3, N)
        [m], table axes (:meth:`isolator.simulation.points.PointSet.elastic`).
    stop_time : float
        When the carriages stop [s] (a dotted line).
    """
    styles = {"x": ":", "y": "--", "z": "-"}
    for i, name in enumerate(names):
        colour = f"C{i % 10}"
        for j, axis in enumerate("xyz"):
            if np.any(elastic[i, j]):
                ax.plot(t, elastic[i, j] * 1e6, color=colour, ls=styles[axis], lw=1.0, label=f"{name}:e{axis}")
    if np.isfinite(stop_time):
        ax.axvline(stop_time, color="0.5", ls=":", lw=1)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("elastic translation [um]")
    ax.set_title("the top's bending at the points (elastic translation from the initial equilibrium, table axes)")
    ax.grid(True, alpha=0.3)
    if ax.lines:
        ax.legend(loc="upper right", fontsize=8, ncol=min(6, len(ax.lines)))
