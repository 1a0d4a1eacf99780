"""The control study's time-domain figures: the table's motion and the actuators' forces in its four runs
(:mod:`studies.control`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from isolator import SIGNALS, Response
from isolator.scenario.arguments import check_public

from .figures import save_figure
from .reporting import micro_unit

__all__ = ["COLORS", "RUNS", "forces_figure", "time_figure"]

#: the study's four runs, in order
RUNS = ("passive", "feedforward", "feedback", "both")
#: each run's colour
COLORS = {"passive": "0.35", "feedforward": "tab:blue", "feedback": "tab:orange", "both": "tab:green"}


def time_figure(runs: Mapping[str, Response], path: Path) -> None:
    """The six table signals in each run, the carriages' stop dotted."""
    fig, axes = plt.subplots(3, 2, figsize=(12, 8.5), sharex=True, layout="constrained")
    for i, name in enumerate(SIGNALS):
        ax = axes[i % 3, i // 3]
        scale, unit = micro_unit(name)
        for run, r in runs.items():
            ax.plot(r.t, r.signals[i] * scale, color=COLORS[run], lw=1.0 if run != "passive" else 1.4,
                    ls="--" if run == "both" else "-", label=run)
        ax.set_ylabel(f"{name} [{unit}]")
        ax.grid(True, alpha=0.3)
        stop = runs["passive"].stop_time
        if math.isfinite(stop):
            ax.axvline(stop, color="0.6", lw=0.8, ls=":")
    axes[0, 0].legend(fontsize=9, ncol=2)
    axes[-1, 0].set_xlabel("time [s]")
    axes[-1, 1].set_xlabel("time [s]")
    fig.suptitle(f"Table motion from its initial equilibrium: passive and active ({runs['passive'].name}); "
                 "dotted: the carriages stop")
    save_figure(fig, path)


def forces_figure(runs: Mapping[str, Response], path: Path) -> None:
    """The actuators' forces in the three active runs."""
    fig, axes = plt.subplots(3, 1, figsize=(11, 8), sharex=True, layout="constrained")
    for ax, run in zip(axes, RUNS[1:], strict=True):
        r = runs[run]
        colors = plt.cm.tab20(np.linspace(0, 1, max(len(r.actuator_names), 1)))
        for k, name in enumerate(r.actuator_names):
            ax.plot(r.t, r.actuator_forces[k], lw=0.9, label=name, color=colors[k])
        ax.set_ylabel("force [N]")
        ax.set_title(f"{run}: largest {np.abs(r.actuator_forces).max():.0f} N")
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7, ncol=6)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle("Forces the actuators apply (after saturation and lag)")
    save_figure(fig, path)


check_public(globals())
