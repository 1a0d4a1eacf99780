"""What the studies share in drawing their figures: saving, log axes, grids and missing values."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axis import Axis
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from isolator.scenario.arguments import check_public
from isolator.scenario.output_files import save_figure_file

__all__ = ["log_mesh_edges", "nan_if_none", "plain_log_axis", "save_figure"]

_PLAIN = FuncFormatter(lambda v, _: f"{v:g}")


def save_figure(fig: Figure, path: Path, dpi: int = 120) -> None:
    """Write the figure to ``path`` (whole or not at all) and close it."""
    try:
        save_figure_file(fig, path, dpi=dpi)
    finally:
        plt.close(fig)


def plain_log_axis(axis: Axis) -> None:
    """Log-axis ticks at 1, 2 and 5 per decade, written as plain numbers."""
    axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(_PLAIN)
    axis.set_minor_formatter(NullFormatter())


def log_mesh_edges(values: np.ndarray) -> np.ndarray:
    """Cell edges of a log grid, for pcolormesh."""
    logs = np.log10(values)
    mids = (logs[1:] + logs[:-1]) / 2
    return 10 ** np.concatenate([[2 * logs[0] - mids[0]], mids, [2 * logs[-1] - mids[-1]]])


def nan_if_none(value: float | None) -> float:
    """The value, or NaN for a missing one (a bar or point not drawn)."""
    return math.nan if value is None else value


check_public(globals())
