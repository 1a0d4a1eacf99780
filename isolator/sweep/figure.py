"""A sweep's figure: the largest settling time against the swept values (``isolator sweep --plot``); for a
scenario with a ``[sequence]`` (whose 5 % settling columns are NaN by design) its total time instead.

Two crossed names (a grid): one line per value of the first name (the outer one) against the second; any
other sweep: one panel per swept name (at most four), every design a dot. Designs that did not give a
settling time (tipped, diverged, refused, invalid, failed, or not settled within the run), or no total
time, are marked with a red cross along the top of each panel, so a gap in the curve says why it is there.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from isolator.sweep.result import SweepResult

__all__ = ["plot_sweep"]

#: at most this many swept names get a panel
MAX_PANELS = 4
#: a grid's outer name is drawn as lines when it has at most this many values
MAX_LINES = 12


def plot_sweep(result: SweepResult, title: str = "", grid: bool | None = None,
               labels: Mapping[str, str] | None = None) -> Any:
    """The figure of a sweep's rows (matplotlib ``Figure``).

    Parameters
    ----------
    result : SweepResult
    title : str
        Above the panels (default: the number of designs and how many gave no value to plot).
    grid : bool, optional
        Whether the designs are a crossed grid (lines per outer value); default: two names whose values
        cross completely.
    labels : mapping of str to str, optional
        Axis label per swept name (default the name), e.g. ``"isolators[*].damping (factor)"``.
    """
    import matplotlib.pyplot as plt

    table = result.table()
    sequence = "total_time" in result.columns  # the column ``best`` judges by (sweep.py)
    y = np.asarray(table["total_time" if sequence else "settling_time_max"], dtype=float)
    what = "total time" if sequence else "settling time"
    y_label = "total time of the sequence [s]" if sequence else "largest settling time after the stop [s]"
    status = np.asarray(table["status"], dtype=object)
    names = list(result.names)
    label = {n: (labels or {}).get(n, n) for n in names}
    bad = ~np.isfinite(y)
    why = sorted({"not settled within the run" if s in ("ok", "unsettled") else str(s) for s in status[bad]})
    heading = title or f"{len(y)} designs, {int(bad.sum())} without a {what} ({', '.join(why) or 'none'})"
    crossed = _crossed(table, names) if grid is None else grid
    if crossed:
        fig, ax = plt.subplots(figsize=(8.5, 5), constrained_layout=True)
        _grid_panel(ax, table, names, y, bad, label)
        _failures(ax, np.asarray(table[names[1]], dtype=float), bad, y, what)
        axes = [ax]
    else:
        shown = names[:MAX_PANELS]
        fig, row = plt.subplots(1, len(shown), figsize=(4.6 * len(shown) + 0.8, 4.4), squeeze=False,
                                sharey=True, constrained_layout=True)
        axes = list(row[0])
        for ax, name in zip(axes, shown, strict=True):
            x = np.asarray(table[name], dtype=float)
            ax.plot(x[~bad], y[~bad], "o", ms=3, alpha=0.7, color="tab:blue", label="designs")
            _failures(ax, x, bad, y, what)
            ax.set_xlabel(label[name])
            _log_if_wide(ax, x)
    axes[0].set_ylabel(y_label)
    for ax in axes:
        ax.grid(True, alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8, title=label[names[0]] if crossed else None, title_fontsize=8)
    fig.suptitle(heading, fontsize=10)
    return fig


def _crossed(table: dict[str, np.ndarray], names: list[str]) -> bool:
    if len(names) != 2:
        return False
    a, b = (np.asarray(table[n], dtype=float) for n in names)
    return len(np.unique(a)) * len(np.unique(b)) == a.size and len(np.unique(a)) <= MAX_LINES


def _grid_panel(ax: Any, table: dict[str, np.ndarray], names: list[str], y: np.ndarray, bad: np.ndarray,
                label: Mapping[str, str]) -> None:
    import matplotlib.pyplot as plt

    outer, inner = (np.asarray(table[n], dtype=float) for n in names)
    levels = np.unique(outer)
    colours = plt.get_cmap("viridis")(np.linspace(0.0, 0.9, levels.size))
    for level, colour in zip(levels, colours, strict=True):
        pick = (outer == level) & ~bad
        order = np.argsort(inner[pick])
        ax.plot(inner[pick][order], y[pick][order], "o-", ms=3, lw=1.3, color=colour, label=f"{level:.4g}")
    ax.set_xlabel(label[names[1]])
    _log_if_wide(ax, inner)


def _failures(ax: Any, x: np.ndarray, bad: np.ndarray, y: np.ndarray, what: str) -> None:
    """Red crosses along the top for the designs without a value (a settling or total time)."""
    if not bad.any():
        return
    known = y[~bad]
    top = float(np.max(known)) * 1.08 if known.size else 1.0
    ax.plot(x[bad], np.full(int(bad.sum()), top), "x", color="tab:red", ms=5, label=f"no {what}")


def _log_if_wide(ax: Any, x: np.ndarray) -> None:
    finite = x[np.isfinite(x)]
    if finite.size and np.all(finite > 0) and finite.max() / finite.min() > 20:
        from matplotlib.ticker import FuncFormatter

        ax.set_xscale("log")
        plain = FuncFormatter(lambda v, _: f"{v:g}")
        ax.xaxis.set_major_formatter(plain)
        ax.xaxis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:g}" if f"{v:.0e}"[0] in "235" else ""))
    if finite.size and math.isclose(float(finite.min()), float(finite.max())):
        ax.set_xlim(float(finite.min()) - 1, float(finite.max()) + 1)
