"""The bending-top case's figures and report section (:mod:`studies.control_bending`)."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from controllers.feedback.output_tuning import PHASE_MARGIN
from controllers.feedback.rolloff import MIN_DISK_MARGIN
from isolator.scenario.arguments import check_public

from .control_bending import TOPS, BendingCase
from .figures import save_figure
from .reporting import fmt, table_header, table_row

__all__ = ["FIGURES", "bending_figures", "bending_report"]

#: the case's figures
FIGURES = ("bending-defaults.png", "bending-compliance.png")
_COLORS = {"rigid": "tab:blue", "bending": "tab:red"}
#: what a missing value means: not settled in the run; no loop's gain crosses 1 (phase) or no gain above 1
#: destabilises (gain)
_NONE = {"settling": "not settled", "disk_margin": "n/a", "phase_margin": "unlimited", "gain_margin": "unlimited"}
#: the least margins a default design keeps (drawn on the figure)
LIMITS = {"disk_margin": MIN_DISK_MARGIN, "phase_margin": PHASE_MARGIN}


def bending_figures(case: BendingCase, folder: Path) -> None:
    """``bending-defaults.png`` (settling and margins per method on each top) and ``bending-compliance.png``."""
    _defaults_figure(case, folder / "bending-defaults.png")
    _compliance_figure(case, folder / "bending-compliance.png")


def _methods(case: BendingCase) -> list[str]:
    return list(dict.fromkeys(d.method for d in case.designs))


def _defaults_figure(case: BendingCase, path: Path) -> None:
    methods = _methods(case)
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.4), layout="constrained")
    x = np.arange(len(methods))
    panels = (("settling", "settling of the move, slowest signal [s]", "settling time"),
              ("disk_margin", "multiloop disk margin [-]", "worst disk margin over the travel"),
              ("phase_margin", "loop-at-a-time phase margin [deg]", "worst phase margin over the travel"))
    for ax, (what, label, title) in zip(axes, panels, strict=True):
        for k, top in enumerate(TOPS):
            values, texts = [], []
            for method in methods:
                d = next((d for d in case.designs if d.method == method and d.top == top), None)
                value = None if d is None else (d.settling if what == "settling" else d.margin(what))
                values.append(math.nan if value is None else value)
                texts.append("n/a" if d is None else _NONE[what] if value is None or math.isnan(value) else
                             f"{value:.3g}")
            bars = ax.bar(x + (k - 0.5) * 0.38, np.nan_to_num(values), 0.38, color=_COLORS[top], label=f"{top} top")
            for bar, v, text in zip(bars, values, texts, strict=True):
                ax.annotate(text, (bar.get_x() + bar.get_width() / 2, 0 if not math.isfinite(v) else v),
                            ha="center", va="bottom", fontsize=8)
        if what in LIMITS:
            ax.axhline(LIMITS[what], color="0.3", ls="--", lw=1.0, label=f"the designs' least ({LIMITS[what]:g})")
        ax.set_xticks(x, [m + ("" if case.searched else " (own weights)") for m in methods])
        ax.set_ylabel(label)
        ax.set_title(title)
        ax.grid(True, axis="y", alpha=0.3)
        ax.set_ylim(0.0, 1.4 * max(ax.get_ylim()[1], LIMITS.get(what, 0.0)))  # room for the legend above the bars
        ax.legend(fontsize=8, loc="upper right")
    rolled = [f"{d.method} at {d.rolloff_hz:.0f} Hz" for d in case.designs if d.rolloff_hz is not None]
    fig.suptitle("Default sensor-based designs on the rigid and on the bending top (each judged on its own top; "
                 f"rolled off on the bending top: {', '.join(rolled) or 'none'})")
    save_figure(fig, path)


def _compliance_figure(case: BendingCase, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(10, 5.5), layout="constrained")
    for name, values in case.compliance.items():
        top = name.split(",")[0]
        ax.loglog(case.frequency_hz, np.abs(values), color=_COLORS[top], ls="--" if "open" in name else "-",
                  lw=1.1 if "open" in name else 1.6, label=f"{name} loop" if "open" in name else name)
    shown = sorted((f, n) for n, f in case.elastic_hz.items() if f <= case.frequency_hz[-1])
    labelled = 0.0
    for k, (f, _) in enumerate(shown):
        ax.axvline(f, color="0.6", lw=0.7, ls=":", label="the bending top's elastic modes" if k == 0 else None)
        if f >= 1.1 * labelled:  # one label for modes closer than 10 %
            labelled = f
            ax.annotate(", ".join(n for g, n in shown if f <= g < 1.1 * f), (f, 0.98),
                        xycoords=("data", "axes fraction"), rotation=90, fontsize=7, va="top", ha="right",
                        color="0.35")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(f"compliance at the corner, {case.axis} per force {case.axis} [m/N]")
    ax.set_title("Compliance at the top's corner: open and closed loop, rigid and bending top\n(carriages at their "
                 "start; the closed loop sampled, up to 0.45 x its sample rate)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    save_figure(fig, path)


def _peak(f: np.ndarray, values: np.ndarray, lo: float, hi: float) -> str:
    inside = (f >= lo) & (f <= hi)
    if not inside.any():
        return "n/a"
    k = int(np.argmax(np.abs(values) * inside))
    return f"{abs(values[k]):.3g} m/N at {f[k]:.4g} Hz"


def bending_report(case: BendingCase | None) -> list[str]:
    """The report's section (none without a case)."""
    if case is None:
        return []
    how = "as `isolator controller` makes them (searched weights)" if case.searched else \
        "with the methods' own weights (quick: skyhook only, no search)"
    lines = ["## On a bending top", "",
             f"The default sensor-based designs {how}, each made for its top and judged on it: the bending top's "
             "design is made on the rigid-body model and judged on the full plant with the elastic modes, rolled "
             "off above the isolation band where it would be unstable or short of a 0.5 disk margin there. The "
             "settling is the move's, simulated with the controller in the loop (the elastic modes included on the "
             "bending top), in the study's band; the margins are the worst over the travel and the isolators' "
             "uncertainty.", "",
             *table_header(["design", "top", "settling, slowest", "peak force", "spectral radius", "disk margin",
                            "gain margin", "phase margin", "roll-off"])]
    for d in case.designs:
        data = d.to_dict()
        lines.append(table_row([d.method, d.top, fmt(d.settling, suffix=" s"), f"{d.peak_force:.3g} N",
                                f"{data['spectral_radius']:.6f}", fmt(data["disk_margin"]),
                                fmt(data["gain_margin"]) if data["gain_margin"] is not None else _NONE["gain_margin"],
                                fmt(data["phase_margin"], ".3g", " deg") if data["phase_margin"] is not None else
                                _NONE["phase_margin"],
                                "none" if d.rolloff_hz is None else f"low-pass at {d.rolloff_hz:.3g} Hz"]))
    lines += ["", *(f"- {name} left out: {why}" for name, why in case.left_out.items())]
    f = case.frequency_hz
    band_top = min(case.elastic_hz.values(), default=f[-1]) / 2
    lines += ["### Compliance at the corner", "",
              f"A unit force at the top's corner along {case.axis}, the corner's displacement along it (carriages at "
              "their start; the closed loop through the sampled controller, hold, lags and delay): the largest "
              f"values in the isolation band (1-{band_top:.3g} Hz) and above it.", "",
              *table_header(["curve", f"largest 1-{band_top:.3g} Hz", f"largest {band_top:.3g}-{f[-1]:.4g} Hz"])]
    for name, values in case.compliance.items():
        lines.append(table_row([name, _peak(f, values, 1.0, band_top), _peak(f, values, band_top, f[-1])]))
    s = case.stiff
    rolled = s.rolled.settings.get("rolloff", {})
    lines += ["", "### A stiff design that the check refuses", "",
              f"Skyhook at {s.gain:g} N s/m with one sample of delay, made on the rigid top: on the rigid top "
              f"{s.rigid.describe()}; on the bending top `isolator check-controller` refuses it: "
              f"{s.bending.describe()}.",
              "The same design made on the bending top is rolled off "
              f"({rolled.get('kind', 'none')} at {fmt(rolled.get('corner_hz'), '.3g', ' Hz')}; "
              f"{rolled.get('reason', '')}): spectral radius {s.rolled_loop.spectral_radius:.6f} "
              f"({'stable' if s.rolled_loop.stable else 'UNSTABLE'}).", ""]
    return lines


check_public(globals())
