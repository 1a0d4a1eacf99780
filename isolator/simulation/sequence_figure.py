"""The figure of a step-and-settle sequence: the point's deviation from each step's settled position against
time, the window shaded, each step's move, settle and measure as coloured spans."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from isolator.simulation.sequence_result import SequenceResult

__all__ = ["PHASE_COLOURS", "plot_sequence"]

#: the spans' colours: move, settle, measure
PHASE_COLOURS = {"move": "#9ecae1", "settle": "#fdd0a2", "measure": "#a1d99b"}


def plot_sequence(result: SequenceResult, point: str | None = None, title: str | None = None) -> Any:
    """Two panels sharing time: above, the deviation of ``point`` (default: the first window's) from each
    step's settled position on the windows' axes [nm], the window band shaded, the vertical axis limited to
    a few windows' widths (the moves' excursions are clipped; they are microns); below, the carriages'
    coordinates [mm]. Every step's move, settle and measure are coloured spans behind both panels."""
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
        for kind, a, b in spans:
            if b > a:
                for axis in (ax, axq):
                    axis.axvspan(a, b, color=PHASE_COLOURS[kind], alpha=0.55, lw=0, zorder=0)
    width = max((w.translation for w in windows if w.point == name), default=0.0) * 1e9
    if name is not None and name in result.point_names:
        dev = result.deviation(name) * 1e9
        axes = sorted({a for w in windows if w.point == name for a in w.axes}, key="xyz".index) or ["x", "y", "z"]
        colours = {"x": "tab:blue", "y": "tab:orange", "z": "tab:purple"}
        for a in axes:
            ax.plot(result.t, dev["xyz".index(a)], lw=0.8, color=colours[a], label=f"{name}:{a}", zorder=3)
    if width > 0:
        ax.axhspan(-width, width, color="tab:green", alpha=0.18, lw=0, zorder=1)
        ax.axhline(width, color="tab:green", lw=0.6, zorder=2)
        ax.axhline(-width, color="tab:green", lw=0.6, zorder=2)
        ax.set_ylim(-5 * width, 5 * width)
    ax.set_ylabel("deviation from the step's\nsettled position [nm]")
    ax.grid(True, alpha=0.3, zorder=0)
    handles, _ = ax.get_legend_handles_labels()
    handles += [Patch(color="tab:green", alpha=0.3, label=f"window ±{width:.4g} nm")] if width > 0 else []
    handles += [Patch(color=c, alpha=0.55, label=k) for k, c in PHASE_COLOURS.items()]
    ax.legend(handles=handles, loc="upper right", fontsize=8, ncol=len(handles), framealpha=0.9)
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
    fig.suptitle(title or f"{result.name}: step and settle ({verdict}; measure {result.measure:g} s)")
    return fig
