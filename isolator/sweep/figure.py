"""A sweep's figure: the largest settling time against the swept values (``isolator sweep --plot``); for a
scenario with a ``[sequence]`` (whose 5 % settling columns are NaN by design) its total time instead.

Two crossed names (a grid): one line per value of the first name (the outer one) against the second; any
other sweep: one panel per swept name (at most four), every design a dot. Designs that did not give a
settling time (tipped, diverged, refused, invalid, failed, or not settled within the run), or no total
time, are red crosses in a strip of their own above each panel (a row per outer value of a grid, in its
colour), with a legend entry, so a gap in the curve says why it is there without a made-up time. An axis
of factors (``scale``) says so; an axis of values names its unit.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from isolator.sweep.result import SweepResult

__all__ = ["axis_label", "plot_sweep"]

#: at most this many swept names get a panel
MAX_PANELS = 4
#: a grid's outer name is drawn as lines when it has at most this many values
MAX_LINES = 12
#: the unit of a swept value by its field's name (the word after the element, ``isolators[*].stiffness.z``)
UNITS = {"stiffness": "N/m", "damping": "N s/m", "mass": "kg", "position": "m", "origin": "m", "inertia": "kg m^2",
         "velocity": "m/s", "acceleration": "m/s^2", "jerk": "m/s^3", "max_force": "N", "bandwidth": "Hz",
         "area": "m^2", "volume": "m^3", "damping_volume": "m^3", "diameter": "m", "length": "m", "t0": "s",
         "stroke": "m", "start": "m", "deceleration": "m/s^2"}


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
        Axis label per swept name; default the name with its unit, or "factor on the scenario's value"
        for a name swept by factors (``result.scaled``).

    Returns
    -------
    matplotlib.figure.Figure
        The figure: the panels, and above them the strip of designs without a value when there are any.
    """
    import matplotlib.pyplot as plt

    table = result.table()
    sequence = "total_time" in result.columns  # the column ``best`` judges by (sweep.py)
    y = np.asarray(table["total_time" if sequence else "settling_time_max"], dtype=float)
    what = "total time" if sequence else "settling time"
    y_label = "total time of the sequence [s]" if sequence else "largest settling time after the stop [s]"
    status = np.asarray(table["status"], dtype=object)
    names = list(result.names)
    label = {n: (labels or {}).get(n) or axis_label(n, n in result.scaled) for n in names}
    bad = ~np.isfinite(y)
    why = sorted({"not settled within the run" if s in ("ok", "unsettled") else str(s) for s in status[bad]})
    heading = title or f"{len(y)} designs, {int(bad.sum())} without a {what} ({', '.join(why) or 'none'})"
    crossed = _crossed(table, names) if grid is None else grid
    shown = names[:2] if crossed else names[:MAX_PANELS]
    columns = 1 if crossed else len(shown)
    rows = 2 if bad.any() else 1
    fig, cells = plt.subplots(rows, columns, figsize=(8.5 if crossed else 4.6 * columns + 0.8, 5 if crossed else 4.4),
                              squeeze=False, sharex="col", sharey="row", constrained_layout=True,
                              height_ratios=[1, 6] if rows == 2 else None)
    axes, strips = list(cells[-1]), (list(cells[0]) if rows == 2 else [None] * columns)
    if crossed:
        levels, colours = _grid_panel(axes[0], table, names, y, bad, label)
        outer = np.asarray(table[names[0]], dtype=float)
        _failures(strips[0], np.asarray(table[names[1]], dtype=float), bad, what, outer, levels, colours)
    else:
        for ax, strip, name in zip(axes, strips, shown, strict=True):
            x = np.asarray(table[name], dtype=float)
            ax.plot(x[~bad], y[~bad], "o", ms=3, alpha=0.7, color="tab:blue", label="designs")
            _failures(strip, x, bad, what)
            ax.set_xlabel(label[name])
            _log_if_wide(ax, x)
    axes[0].set_ylabel(y_label)
    for ax, strip in zip(axes, strips, strict=True):
        ax.grid(True, alpha=0.3)
        handles, texts = ax.get_legend_handles_labels()
        if strip is not None:
            extra = strip.get_legend_handles_labels()
            handles, texts = handles + extra[0][:1], texts + extra[1][:1]
        if handles:
            ax.legend(handles, texts, fontsize=8, title=label[names[0]] if crossed else None, title_fontsize=8)
    fig.suptitle(heading, fontsize=10)
    return fig


def axis_label(name: str, factor: bool) -> str:
    """The axis label of a swept name: a factor on the scenario's value, or the value with its unit.

    Parameters
    ----------
    name : str
        The swept name, e.g. ``isolators[*].stiffness.z``.
    factor : bool
        Whether its values are factors (``scale``) rather than values (``set``).

    Returns
    -------
    str
        E.g. ``isolators[*].stiffness.z: factor on the scenario's value [-]`` or
        ``isolators[*].stiffness.z [N/m]``.

    Examples
    --------
    >>> axis_label("isolators[*].damping", True)
    "isolators[*].damping: factor on the scenario's value [-]"
    >>> axis_label("carriages[0].mass", False)
    'carriages[0].mass [kg]'
    """
    if factor:
        return f"{name}: factor on the scenario's value [-]"
    fields = [part.split("[")[0] for part in name.split(".")]
    unit = next((UNITS[f] for f in reversed(fields) if f in UNITS), None)
    return f"{name} [{unit}]" if unit else name


def _crossed(table: dict[str, np.ndarray], names: list[str]) -> bool:
    if len(names) != 2:
        return False
    a, b = (np.asarray(table[n], dtype=float) for n in names)
    return len(np.unique(a)) * len(np.unique(b)) == a.size and len(np.unique(a)) <= MAX_LINES


def _grid_panel(ax: Any, table: dict[str, np.ndarray], names: list[str], y: np.ndarray, bad: np.ndarray,
                label: Mapping[str, str]) -> tuple[np.ndarray, np.ndarray]:
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
    return levels, colours


def _failures(strip: Any, x: np.ndarray, bad: np.ndarray, what: str, outer: np.ndarray | None = None,
              levels: np.ndarray | None = None, colours: np.ndarray | None = None) -> None:
    """Crosses in the strip above a panel for the designs without a value (a settling or total time): one
    row per outer value of a grid, edged in its line's colour."""
    if strip is None:
        return
    from matplotlib.lines import Line2D

    grid = outer is not None and levels is not None and colours is not None
    rows = np.searchsorted(levels, outer[bad]) if grid else np.zeros(int(bad.sum()), dtype=int)  # type: ignore[arg-type, index]
    colour = colours[rows] if grid else "tab:red"  # type: ignore[index]
    strip.scatter(x[bad], rows, marker="x", c=colour, s=30, linewidths=1.5)
    where = "strip above, in its line's colour" if grid else "strip above"
    strip.add_line(Line2D([], [], marker="x", ls="", color="tab:red" if not grid else "0.25",
                          label=f"no {what} within the run ({where})"))
    count = 1 if levels is None else levels.size
    strip.set_ylim(-0.7, count - 0.3)
    strip.set_yticks([])
    strip.set_ylabel(f"no {what}", rotation=0, ha="right", va="center", fontsize=8)
    strip.tick_params(axis="x", labelbottom=False)
    strip.grid(True, axis="x", alpha=0.3)


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
