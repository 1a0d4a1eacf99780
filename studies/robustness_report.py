"""The robustness study's figures and ``report.md`` (:mod:`studies.robustness`)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from isolator.scenario.arguments import check_public

from .figures import save_figure
from .reporting import band_lines, fmt, table_header, table_row, write_report
from .robustness_results import RobustnessStudy

__all__ = ["plot_cdf", "plot_sensitivity", "write_robustness_report"]

_COLOURS = {"paper": "0.3", "ZVD": "tab:blue", "optimised": "tab:red"}
#: parameters shown in the sensitivity figure, at most
_SHOWN = 14


def _colour(name: str) -> str:
    return _COLOURS.get(name, "tab:green")


def _ecdf(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sorted finite values and their cumulative share of all machines, starting at the share below the
    first (machines at -inf), ending below 1 when some are at +inf or NaN; empty when none is finite."""
    finite = np.sort(values[np.isfinite(values)])
    below = float(np.isneginf(values).sum()) / max(values.size, 1)
    share = below + np.arange(1, finite.size + 1) / max(values.size, 1)
    return np.concatenate([finite[:1], finite]), np.concatenate([[below], share])[: finite.size + 1]


def _curve(ax: Any, values: np.ndarray, colour: str, label: str) -> None:
    """An ECDF step curve, or only a legend entry when no machine has a finite value."""
    x, y = _ecdf(values)
    if x.size:
        ax.step(x, y, where="post", color=colour, lw=1.6, label=label)
    else:
        ax.plot([], [], color=colour, lw=1.6, label=f"{label} (no machine settles)")


def plot_cdf(study: RobustnessStudy) -> Path:
    """``cdf.png``: each method's settling-time distribution, and its benefit over the paper profile."""
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 5), constrained_layout=True)
    for name, m in study.methods.items():
        _curve(ax, m.settling_time, _colour(name),
               f"{name}: P50 {fmt(m.percentile(50))} s, P95 {fmt(m.percentile(95))} s")
        p95 = m.percentile(95)
        if math.isfinite(p95):
            ax.plot([p95], [0.95], "o", color=_colour(name), ms=5)
        if m.nominal is not None:
            ax.axvline(m.nominal, color=_colour(name), ls=":", lw=1)
    ax.axhline(0.95, color="0.6", lw=0.8, ls="--")
    ax.set_xlabel("largest settling time after the stop [s]")
    ax.set_ylabel("share of machines settled [-]")
    ax.set_ylim(0, 1.02)
    ax.set_title(f"Settling time over {study.samples.shape[0]} machines within tolerance\n"
                 "(dots: P95; dotted: the nominal machine)", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    for name in study.methods:
        if name == "paper":
            continue
        b = study.benefit(name)
        only = [f"{int(np.isneginf(b).sum())} where only {name} does not settle" if np.isneginf(b).any() else "",
                f"{int(np.isposinf(b).sum())} where only the paper profile does not" if np.isposinf(b).any() else ""]
        note = "; ".join(t for t in only if t)
        _curve(bx, b, _colour(name), name + (f" ({note}: off the axis)" if note else ""))
    bx.axvline(0.0, color="k", lw=0.8)
    bx.set_xlabel("cycle time (move + settling) saved against the paper profile\non the same machine [s]")
    bx.set_ylabel("share of machines [-]")
    bx.set_ylim(0, 1.02)
    bx.set_title("Benefit of each profile, machine by machine, its longer move counted\n(right of 0: a shorter "
                 "cycle than the paper profile's)", fontsize=10)
    bx.grid(True, alpha=0.3)
    bx.legend(fontsize=8, loc="upper left")
    fig.suptitle(f"{study.scenario.name}: robustness of the settling time (band: {study.band.how()})", fontsize=11)
    path = study.folder / "cdf.png"
    save_figure(fig, path)
    return path


def plot_sensitivity(study: RobustnessStudy) -> Path:
    """``sensitivity.png``: Spearman's rank correlation of each varied parameter with the settling time."""
    ranking = study.ranking("paper")[:_SHOWN]
    names = [n for n, _ in ranking]
    index = {v.name: j for j, v in enumerate(study.varied)}
    fig, ax = plt.subplots(figsize=(10, 0.45 * len(names) + 1.8), constrained_layout=True)
    methods = list(study.methods)
    height = 0.8 / len(methods)
    y = np.arange(len(names))
    for k, name in enumerate(methods):
        rho = study.sensitivity(name)
        ax.barh(y + (k - (len(methods) - 1) / 2) * height, [rho[index[n]] for n in names], height,
                color=_colour(name), label=name)
    ax.set_yticks(y, names, fontsize=8)
    ax.invert_yaxis()
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlim(-1, 1)
    ax.set_xlabel("rank correlation with the settling time (Spearman) [-]")
    ax.set_title("Which tolerances matter most (largest |correlation| for the paper profile first)", fontsize=10)
    ax.grid(True, axis="x", alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    path = study.folder / "sensitivity.png"
    save_figure(fig, path)
    return path


def _benefit(value: float | str | None) -> str:
    if isinstance(value, str):
        return "+∞ (the paper profile does not settle)" if value == "+inf" else "−∞ (the method does not settle)"
    return fmt(value)


def write_robustness_report(study: RobustnessStudy) -> Path:
    """``report.md``: tolerances, the settling time's spread per method, benefits, the ranking."""
    n = study.samples.shape[0]
    lines = [f"# Robustness of the settling time: {study.scenario.name}", "",
             f"{n} machines drawn within the tolerances (uniform, Latin hypercube); every element varies on its "
             "own. Each machine runs the scenario's own profile (paper), the ZVD-shaped profile and the profile "
             "optimised on the nominal machine.", "", "## Tolerances", ""]
    lines += [f"- `{label}`" for label in sorted({v.tolerance.label for v in study.varied})]
    lines += ["", f"{len(study.varied)} independently varied parameters (relative tolerances scale an element's "
              "components together; absolute ones vary each component).", "", "## Settling time", ""]
    lines += table_header(["method", "move [s]", "nominal [s]", "P50 [s]", "P95 [s]", "worst [s]",
                           "cycle P50 [s]", "cycle P95 [s]", "no settling time"])
    for name, m in study.methods.items():
        lines.append(table_row([name, fmt(m.move_time, ".3f"), fmt(m.nominal), fmt(m.percentile(50)),
                                fmt(m.percentile(95)), fmt(m.worst), fmt(m.percentile(50, "cycle"), ".3f"),
                                fmt(m.percentile(95, "cycle"), ".3f"), f"{m.failed} of {n}"]))
    lines += ["", "Settling after the stop; cycle = move (from the command to the stop) + settling. Percentiles are "
              "upper order statistics (of the n sorted machines, the one of rank ceil(q/100 (n - 1)) + 1: with 20 "
              "machines or fewer, P95 is the worst); a machine without a settling time (it tips, diverges or does "
              "not settle within the run) counts as slower than any.", "",
              "## Benefit over the paper profile, machine by machine", "",
              "The paper profile's cycle minus the method's on the same machine: a shaped move's extra length "
              "counts against it. Percentiles are lower order statistics (the rank floor(q/100 (n - 1)) + 1 of "
              "the n machines compared), the side that does not flatter the method; +inf: only the paper profile "
              "does not settle, -inf: only the method does not; machines where neither settles are left out.", ""]
    lines += table_header(["method", "P5 [s]", "P50 [s]", "P95 [s]", "faster on", "only this one unsettled",
                           "only the paper's unsettled"])
    data = study.to_dict()["methods"]
    for name in study.methods:
        if name == "paper":
            continue
        b = data[name]["benefit"]
        share = "n/a" if b["better_share"] is None else f"{b['better_share'] * 100:.0f} % of {b['compared']} machines"
        lines.append(table_row([name, *(_benefit(b[f"p{q}"]) for q in (5, 50, 95)), share,
                                b["only_method_unsettled"], b["only_paper_unsettled"]]))
    lines += ["", "## What matters most", "",
              "Spearman's rank correlation of each varied parameter with the settling time (machines without one "
              "ranked slowest); positive: a larger value settles later.", ""]
    lines += table_header(["parameter", *study.methods])
    rhos = {name: dict(study.ranking(name)) for name in study.methods}
    for name, _ in study.ranking("paper")[:_SHOWN]:
        lines.append(table_row([f"`{name}`", *(fmt(rhos[m][name], "+.2f") for m in study.methods)]))
    lines += ["", "## Band", ""]
    lines += band_lines(study.band, "The paper profile's peaks on the nominal machine: one band for every run "
                        "and method.")
    lines += ["", "Figures: `cdf.png`, `sensitivity.png`; every machine: `samples.csv`."]
    return write_report(study.folder, lines)


check_public(globals())
