"""The error budget's figure: per point and axis the amplitude spectral density of every source and of the
total on log-log axes, the cumulative RMS on a second axis, and the specification where one is given.

The total is drawn first, wide and pale, so that the source that makes it shows on top of it; the sources take
colours that neither the cumulative RMS (red, dashed) nor the specification (purple, dotted) use."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from isolator.scenario.readable import number_text

from .units import AXES, display_unit

__all__ = ["budget_figure"]

#: sources of a panel drawn in colour with their own legend entry (the largest); the others thin and grey
_SHOWN = 6
#: the sources' colours: tab10 without its red (the cumulative RMS) and purple (the specification)
_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:brown", "tab:pink", "tab:olive", "tab:cyan")
#: the width [inch] of a character of a frequency tick's label, and the room between two labels
_CHARACTER, _GAP = 0.085, 0.12


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
    floor_value = max(float(total.max(initial=0.0)) * scale * 1e-8, 1e-30)

    def shown(curve: np.ndarray) -> np.ndarray:  # zero outside a source's range: a gap, not a cliff
        return np.where(curve > floor_value, curve, np.nan)

    def amount(value: float) -> str:
        return f"{number_text(value * scale)} {unit}"
    for i, point in enumerate(budget.points):
        for j, axis in enumerate(AXES):
            ax = axes[i, j]
            ax.loglog(f, shown(total[i, j] * scale), color="k", lw=4.0, alpha=0.3, zorder=1,
                      label=f"total ({amount(rms[i, j])} RMS)")
            ranked = [int(k) for k in np.argsort(parts[i, j])[::-1] if parts[i, j, k] > 0]
            for rank, k in enumerate(ranked[:_SHOWN]):  # the largest drawn last, on top
                ax.loglog(f, shown(asd[i, j, k] * scale), lw=1.2, color=_COLOURS[rank % len(_COLOURS)],
                          zorder=3 + _SHOWN - rank, label=f"{budget.sources[k]} ({amount(parts[i, j, k])})")
            rest = ranked[_SHOWN:]
            for n, k in enumerate(rest):  # every source is drawn; the smaller ones thin and grey, one legend entry
                ax.loglog(f, shown(asd[i, j, k] * scale), lw=0.6, color="0.6", zorder=2,
                          label=f"{len(rest)} smaller source{'s' if len(rest) > 1 else ''}, each at most "
                          f"{amount(parts[i, j, rest[0]])}" if n == 0 else None)
            ax.set_xlabel("frequency [Hz]")
            ax.set_ylabel(f"ASD [{unit}/√Hz]")
            ax.grid(True, which="both", alpha=0.3)
            twin = ax.twinx()
            twin.plot(f, cumulative[i, j] * scale, color="tab:red", ls="--", lw=1.5, label="cumulative RMS")
            spec = specification.get((point, axis))
            if spec is not None:
                twin.axhline(spec * scale, color="tab:purple", ls=":", lw=1.5,
                             label=f"specification {amount(spec)}")
            twin.set_ylabel(f"cumulative RMS from {budget.band[0]:g} Hz [{unit}]", color="tab:red")
            twin.set_ylim(bottom=0.0, top=max(float(cumulative[i, j, -1]) * scale,
                                              (spec or 0.0) * scale, 1e-30) * 1.15)
            ax.set_xlim(f[0], f[-1])
            _frequency_ticks(ax, float(f[0]), float(f[-1]))
            ax.set_title(f"{point}: {axis}", fontsize=10)
            handles, labels = ax.get_legend_handles_labels()
            more, more_labels = twin.get_legend_handles_labels()
            twin.legend(handles + more, labels + more_labels, fontsize=7, loc="upper right")  # above both curves
            top = float(np.nanmax(total[i, j])) * scale if total[i, j].size else 1.0
            ax.set_ylim(max(top * 1e-7, floor_value), max(top, floor_value * 10) * 30)
    loop = "passive table" if budget.controller is None else f"closed loop ({budget.controller})"
    fig.suptitle(f"{title or 'Error budget'}: {budget.quantity} at the points, {loop}, "
                 f"{budget.band[0]:g} to {budget.band[1]:g} Hz")
    return fig


def _frequency_ticks(ax: Any, low: float, high: float) -> None:
    """Frequency ticks [Hz] as plain numbers (``%g``) that do not run into each other on the axis: at powers of
    ten with 2 and 5 between them, or at powers of ten only, or every few decades, whichever first leaves
    :data:`_GAP` between neighbouring labels (each :data:`_CHARACTER` per character); over a band that holds
    fewer than two of those, a few evenly spaced ones."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, LogLocator, MaxNLocator, NullFormatter, NullLocator

    width = ax.get_position().width * ax.figure.get_figwidth()  # [inch]
    decades = math.log10(high / low)

    def fit(ticks: Any) -> list[float]:  # those inside the band, if at least two and no labels collide
        inside = [float(t) for t in ticks if low * (1 - 1e-9) <= t <= high * (1 + 1e-9)]
        at = [math.log10(t / low) / decades * width for t in inside]
        size = [_CHARACTER * len(f"{t:g}") for t in inside]
        clear = all(at[k + 1] - at[k] >= (size[k] + size[k + 1]) / 2 + _GAP for k in range(len(inside) - 1))
        return inside if len(inside) >= 2 and clear else []

    for subs in ((1.0, 2.0, 5.0), (1.0,)):
        for count in range(12, 1, -1):
            major = LogLocator(base=10.0, subs=subs, numticks=count)
            if fit(major.tick_values(low, high)):
                ax.xaxis.set_major_locator(major)
                minor = LogLocator(base=10.0, subs=tuple(float(k) for k in range(2, 10)), numticks=count)
                ax.xaxis.set_minor_locator(minor)
                break
        else:
            continue
        break
    else:  # a short band: evenly spaced
        ticks = next((t for n in (4, 3, 2, 1) if (t := fit(MaxNLocator(nbins=n).tick_values(low, high)))),
                     [low, high])
        ax.xaxis.set_major_locator(FixedLocator(ticks))
        ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())
