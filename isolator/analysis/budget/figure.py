"""The error budget's figure: per point and axis the amplitude spectral density of every source and of the
total on log-log axes, the cumulative RMS on a second axis, and the specification where one is given."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .units import AXES, display_unit

__all__ = ["budget_figure"]

#: sources of a panel drawn in colour with their own legend entry (the largest); the others thin and grey
_SHOWN = 6


def budget_figure(budget: Any, specification: Mapping[tuple[str, str], float], title: str = "") -> Any:
    """Draw ``budget``; ``specification`` maps ``(point, axis)`` to an allowed RMS [SI] drawn on the cumulative
    axis. Returns the figure."""
    import matplotlib.pyplot as plt

    scale, unit = display_unit(budget.quantity)
    rows, cols = len(budget.points), len(AXES)
    fig, axes = plt.subplots(rows, cols, figsize=(5.0 * cols, 3.8 * rows + 0.8), squeeze=False,
                             constrained_layout=True)
    f = budget.frequency
    asd, total, cumulative, rms = budget.asd, np.sqrt(budget.total_psd), budget.cumulative, budget.rms
    parts = budget.source_rms
    colours = plt.get_cmap("tab10")  # by rank within a panel
    floor_value = max(float(total.max(initial=0.0)) * scale * 1e-8, 1e-30)

    def shown(curve: np.ndarray) -> np.ndarray:  # zero outside a source's range: a gap, not a cliff
        return np.where(curve > floor_value, curve, np.nan)
    for i, point in enumerate(budget.points):
        for j, axis in enumerate(AXES):
            ax = axes[i, j]
            ranked = [int(k) for k in np.argsort(parts[i, j])[::-1] if parts[i, j, k] > 0]
            for rank, k in enumerate(ranked[:_SHOWN]):
                ax.loglog(f, shown(asd[i, j, k] * scale), lw=1.0, color=colours(rank % 10),
                          label=f"{budget.sources[k]} ({parts[i, j, k] * scale:.3g} {unit})")
            rest = ranked[_SHOWN:]
            for n, k in enumerate(rest):  # every source is drawn; the smaller ones thin and grey, one legend entry
                ax.loglog(f, shown(asd[i, j, k] * scale), lw=0.6, color="0.6",
                          label=f"{len(rest)} smaller sources, each" if n == 0 else None)
            ax.loglog(f, shown(total[i, j] * scale), color="k", lw=2.0,
                      label=f"total ({rms[i, j] * scale:.3g} {unit} RMS)")
            ax.set_xlabel("frequency [Hz]")
            ax.set_ylabel(f"ASD [{unit}/√Hz]")
            ax.grid(True, which="both", alpha=0.3)
            twin = ax.twinx()
            twin.plot(f, cumulative[i, j] * scale, color="tab:red", ls="--", lw=1.5, label="cumulative RMS")
            spec = specification.get((point, axis))
            if spec is not None:
                twin.axhline(spec * scale, color="tab:purple", ls=":", lw=1.5,
                             label=f"specification {spec * scale:.3g} {unit}")
            twin.set_ylabel(f"cumulative RMS from {budget.band[0]:g} Hz [{unit}]", color="tab:red")
            twin.set_ylim(bottom=0.0, top=max(float(cumulative[i, j, -1]) * scale,
                                              (spec or 0.0) * scale, 1e-30) * 1.15)
            ax.set_xlim(f[0], f[-1])
            ax.set_title(f"{point}: {axis}", fontsize=10)
            handles, labels = ax.get_legend_handles_labels()
            more, more_labels = twin.get_legend_handles_labels()
            ax.legend(handles + more, labels + more_labels, fontsize=7, loc="upper right")
            top = float(np.nanmax(total[i, j])) * scale if total[i, j].size else 1.0
            ax.set_ylim(max(top * 1e-7, floor_value), top * 30)
    loop = "passive table" if budget.controller is None else f"closed loop ({budget.controller})"
    fig.suptitle(f"{title or 'Error budget'}: {budget.quantity} at the points, {loop}, "
                 f"{budget.band[0]:g} to {budget.band[1]:g} Hz")
    return fig
