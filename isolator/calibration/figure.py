"""The calibration's figure: per table sensor the measured H1 (magnitude and phase, coherence shaded) against
the nominal and the fitted model, the move experiments' traces, and the parameters' fitted values with their
95 % intervals relative to the initial ones."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["calibration_figure"]


def _floor_rows(curves: Any) -> list[tuple[str, int, int]]:
    """(label, sensor, input) per table sensor: the floor input it responds to most."""
    rows = []
    for s, name in enumerate(curves.outputs):
        k = int(np.argmax(np.nanmean(np.abs(curves.measured[s]), axis=1)))
        rows.append((f"{name} / {curves.inputs[k]}", s, k))
    return rows


def calibration_figure(result: Any) -> Figure:
    """A :class:`~isolator.calibration.result.CalibrationResult`'s figure (a matplotlib Figure, not shown)."""
    from matplotlib.figure import Figure

    floors = [(n, c) for n, c in result.curves.items() if c.kind == "floor"]
    moves = [(n, c) for n, c in result.curves.items() if c.kind == "move"]
    rows = max([len(c.outputs) for _, c in floors + moves] + [1])
    cols = 2 * len(floors) + len(moves)
    fig = Figure(figsize=(4.2 * max(cols, 2), 2.1 * rows + 3.2), layout="constrained")
    grid = fig.add_gridspec(rows + 1, max(cols, 2), height_ratios=[1.0] * rows + [1.4])
    col = 0
    for name, c in floors:
        for label, s, k in _floor_rows(c):
            mag, ph = fig.add_subplot(grid[s, col]), fig.add_subplot(grid[s, col + 1])
            shade = mag.twinx()
            coherence = c.coherence if c.coherence is not None else np.ones((len(c.outputs), c.x.size))
            shade.fill_between(c.x, 0, coherence[s], color="0.85", step="mid", label="coherence (right axis)")
            shade.set_ylim(0, 1.05)
            shade.set_yticks([0, 1])
            shade.set_ylabel("coherence [-]", fontsize=7, color="0.45")
            mag.set_zorder(shade.get_zorder() + 1)
            mag.patch.set_visible(False)
            reference = np.unwrap(np.angle(c.fitted[s, k]))  # the fitted model's phase, continuous
            for data, style, lab in ((c.measured, "k.", "measured H1"), (c.nominal, "C0--", "nominal model"),
                                     (c.fitted, "C3-", "fitted model")):
                mag.semilogy(c.x, np.abs(data[s, k]), style, ms=2.5, lw=1.2, label=lab)
                # each curve on the branch nearest the fitted one's: no jumps at +-180 deg, and measured and
                # model phases that agree drawn together (unwrapping each alone may part them by 360 deg)
                ph.plot(c.x, np.degrees(reference + np.angle(data[s, k] / c.fitted[s, k])), style, ms=2.5, lw=1.2)
            mag.set_ylabel("|H| [-]" if c.units[s] else "|H|")
            mag.set_title(f"{name}: {label}", fontsize=8)
            ph.set_ylabel("phase, unwrapped [deg]")
            if s == len(c.outputs) - 1:
                mag.set_xlabel("frequency [Hz]")
                ph.set_xlabel("frequency [Hz]")
            if s == 0:
                lines, texts = mag.get_legend_handles_labels()
                fills, fill_texts = shade.get_legend_handles_labels()
                mag.legend(lines + fills, texts + fill_texts, fontsize=7, loc="lower left")
        col += 2
    for name, c in moves:
        for s, sensor in enumerate(c.outputs):
            ax = fig.add_subplot(grid[s, col])
            ax.plot(c.x, c.measured[s], color="0.6", lw=0.8, label="measured")
            ax.plot(c.x, c.nominal[s], "C0--", lw=1.0, label="nominal model")
            ax.plot(c.x, c.fitted[s], "C3-", lw=1.0, label="fitted model")
            ax.set_ylabel(f"[{c.units[s]}]")
            ax.set_title(f"{name}: {sensor}", fontsize=8)
            if s == 0:
                ax.legend(fontsize=7)
            if s == len(c.outputs) - 1:
                ax.set_xlabel("time [s]")
        col += 1
    ax = fig.add_subplot(grid[rows, :])
    names = list(result.parameters)
    est = list(result.parameters.values())
    y = np.arange(len(names))
    ratio = np.array([e.value / e.initial for e in est])
    low = np.array([e.ci95[0] / e.initial for e in est])
    high = np.array([e.ci95[1] / e.initial for e in est])
    ax.errorbar(ratio, y, xerr=[ratio - low, high - ratio], fmt="o", color="C3", capsize=4,
                label="fitted, 95 % interval")
    ax.plot(np.ones(len(names)), y, "s", color="C0", mfc="none", label="initial (scenario)")
    for i, e in enumerate(est):
        ax.annotate(f"{e.value:.4g} [{e.ci95[0]:.4g}, {e.ci95[1]:.4g}]", (high[i], i), xytext=(6, -3),
                    textcoords="offset points", fontsize=7)
    span = max(float(high.max()), 1.0) - min(float(low.min()), 1.0)
    ax.set_xlim(min(float(low.min()), 1.0) - 0.05 * span, max(float(high.max()), 1.0) + 0.3 * span)  # the labels
    ax.set_yticks(y, names, fontsize=8)
    ax.set_xlabel("value / initial value [-]")
    ax.set_title("fitted parameters" + ("" if result.identifiable else " (NOT identifiable: "
                                        + "; ".join(", ".join(g) for g in result.unidentifiable) + ")"), fontsize=9)
    ax.legend(fontsize=7, loc="lower right")
    ax.grid(axis="x", alpha=0.3)
    fig.suptitle(f"Calibration of {result.calibration.scenario.name}: measured records against the nominal and "
                 "the fitted model")
    return fig
