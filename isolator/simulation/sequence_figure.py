"""The figure of a step-and-settle sequence: the point's deviation from each step's settled position against
time, the window shaded, each step's move, settle and measure as coloured spans."""

from __future__ import annotations

from typing import Any

import numpy as np

from isolator.scenario.readable import length_text

__all__ = ["PHASE_COLOURS", "plot_sequence"]

#: the spans' colours: move, settle, measure
PHASE_COLOURS = {"move": "#9ecae1", "settle": "#fdd0a2", "measure": "#a1d99b"}


def plot_sequence(result: Any, point: str | None = None, title: str | None = None) -> Any:
    """A :class:`~isolator.simulation.sequence_result.SequenceResult`'s figure, two panels sharing time.

    Above, the largest deviation of ``point`` (default: the first window's) from each step's settled
    position over the windows' axes [nm], on a log scale (the moves' microns and the window's nanometres
    in one view), the window shaded, each settled time marked, the steps numbered; below, the carriages'
    coordinates [mm]. Every step's move, settle and measure are coloured spans behind both panels.
    """
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    windows = [w for w in result.windows if point is None or w.point == point]
    name = point if point is not None else (windows[0].point if windows else
                                           (result.point_names[0] if result.point_names else None))
    fig, (ax, axq) = plt.subplots(2, 1, figsize=(12, 6.4), sharex=True, constrained_layout=True,
                                  gridspec_kw={"height_ratios": [3, 1.3]})
    for s in result.steps:
        spans = [("move", s.start, s.stop)]
        if s.settled is not None and s.end is not None:
            spans += [("settle", s.stop, s.settled), ("measure", s.settled, s.end)]
        else:
            spans.append(("settle", s.stop, float(result.t[-1]) if result.t.size else s.stop))
        for kind, a, b in spans:  # a bar along the top of the deviation panel, full height below
            if b > a:
                ax.axvspan(a, b, ymin=0.92, ymax=1.0, color=PHASE_COLOURS[kind], lw=0, zorder=0)
                axq.axvspan(a, b, color=PHASE_COLOURS[kind], alpha=0.55, lw=0, zorder=0)
    width = max((w.translation for w in windows if w.point == name), default=0.0) * 1e9
    axes = sorted({a for w in windows if w.point == name for a in w.axes}, key="xyz".index) or ["x", "y", "z"]
    floor = width / 100 if width > 0 else 1e-3
    if name is not None and name in result.point_names and result.t.size:
        dev = np.abs(result.deviation(name)[["xyz".index(a) for a in axes]]).max(axis=0) * 1e9
        ax.semilogy(result.t, np.maximum(dev, floor), lw=0.7, color="tab:blue", zorder=3,
                    label=f"{name}: largest |deviation| on {','.join(axes)}")
        ax.set_ylim(floor, max(float(dev.max()), 10 * width) * 8.0)  # room for the phase bar
    if width > 0:
        ax.axhspan(floor, width, color="tab:green", alpha=0.18, lw=0, zorder=1)
        ax.axhline(width, color="tab:green", lw=0.8, zorder=2)
    done = [s.settled for s in result.steps if s.settled is not None]
    if done and width > 0:
        ax.plot(done, [width] * len(done), ls="none", marker="v", ms=6, color="tab:green", zorder=4,
                label="settled (measure starts)")
    for s in result.steps:
        ax.annotate(str(s.index), (0.5 * (s.start + s.stop), 1.0), xycoords=("data", "axes fraction"),
                    xytext=(0, -9), textcoords="offset points", ha="center", fontsize=7, color="0.2")
    ax.set_ylabel(f"{name} deviation from the\nstep's settled position [nm]")
    ax.grid(True, which="major", alpha=0.3, zorder=0)
    handles, _ = ax.get_legend_handles_labels()
    handles += [Patch(color="tab:green", alpha=0.3, label=f"window ±{length_text(width * 1e-9)}")] if width > 0 else []
    handles += [Patch(color=c, label=k) for k, c in PHASE_COLOURS.items()]
    ax.legend(handles=handles, loc="lower center", bbox_to_anchor=(0.5, 1.0), fontsize=8, ncol=len(handles),
              frameon=False)
    for i, n in enumerate(result.carriage_names):
        axq.plot(result.t, result.q[i] * 1e3, lw=1.2, label=n)
    axq.set_ylabel("carriage [mm]")
    axq.set_xlabel("time [s]")
    axq.grid(True, alpha=0.3)
    axq.legend(loc="upper right", fontsize=8, ncol=max(1, len(result.carriage_names)))
    if result.t.size:
        axq.set_xlim(float(result.t[0]), float(result.t[-1]))
    total = result.total_time
    rate = result.throughput
    verdict = (f"{len(result.steps)} steps in {total:.3f} s, {rate:.0f} steps per hour" if total is not None
               and rate is not None else f"step {result.unsettled} did not settle within {result.duration:g} s")
    fig.suptitle(title or f"{result.name}: step and settle ({verdict}; measure {result.measure:g} s)",
                 fontsize=11)
    return fig
