"""The trade-off study's figures and report (:mod:`studies.tradeoff`): ``maps.png``, ``tradeoff.png``,
``throughput.png`` (with ``[[windows]]`` or a ``[sequence]``) and ``report.md``."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.legend import Legend
from matplotlib.lines import Line2D

from isolator.scenario.arguments import check_public

from .figures import log_mesh_edges, plain_log_axis, save_figure
from .reporting import band_lines, fmt, table_header, write_report
from .tradeoff_pneumatic import pneumatic_note
from .tradeoff_results import TradeoffStudy

#: where a legend goes in an axes
Corner = Literal["lower left", "upper left", "lower right"]

__all__ = ["plot_maps", "plot_throughput", "plot_tradeoff", "scatter_designs", "write_tradeoff_report"]


def _time_axis(study: TradeoffStudy) -> str:
    if study.sequence:
        return "total time of the sequence [s]"
    return f"largest settling time [s]\n(band: {study.band.how()})"


def plot_maps(study: TradeoffStudy) -> None:
    """``maps.png``: the time figure, transmissibility and resonance peak over the (stiffness, damping) grid."""
    panels = [
        (study.settling_time, _time_axis(study), "viridis", None),
        (study.transmissibility, f"transmissibility at {study.reference_hz:g} Hz [m/m], worst of x, y, z",
         "magma", LogNorm()),
        (study.peak, "resonance peak of the transmissibility [m/m], worst of x, y, z", "magma", LogNorm()),
    ]
    if study.has_throughput:
        panels.insert(1, (study.per_hour, f"{study.rate_label} [1/h]", "cividis", None))
    fig, axes = plt.subplots(1, len(panels), figsize=(5.7 * len(panels), 5.2), constrained_layout=True)
    ke, ce = log_mesh_edges(study.stiffness), log_mesh_edges(study.damping)
    front = study.pareto()
    nominal = study.nominal()
    for ax, (values, label, cmap, norm) in zip(axes, panels, strict=True):
        finite = values[np.isfinite(values)]
        if finite.size:
            mesh = ax.pcolormesh(ce, ke, np.ma.masked_invalid(values), cmap=cmap, norm=norm, shading="flat")
            bar = fig.colorbar(mesh, ax=ax, label=label)
            if norm is not None:
                plain_log_axis(bar.ax.yaxis)
        for i in np.flatnonzero(~study.stable):
            ax.fill_between([ce[0], ce[-1]], ke[i], ke[i + 1], facecolor="0.85", hatch="//", edgecolor="0.5",
                            linewidth=0, label="table tips" if i == np.flatnonzero(~study.stable)[0] else None)
        if front:
            ax.plot([study.damping[j] for _, j in front], [study.stiffness[i] for i, _ in front], "o", ms=5,
                    mfc="white", mec="black", mew=0.8, label="Pareto-optimal")
        if nominal is not None:
            ax.plot(1.0, 1.0, "*", ms=14, mfc="tab:red", mec="white", label="scenario's design")
        ax.set_xscale("log")
        ax.set_yscale("log")
        plain_log_axis(ax.xaxis)
        plain_log_axis(ax.yaxis)
        ax.set_xlabel("damping scale (x the scenario's) [-]")
        ax.set_ylabel("stiffness scale (x the scenario's) [-]")
        ax.set_title(label.split(" [")[0])
        ax.legend(loc="upper left", fontsize=8, framealpha=0.85)
    fig.suptitle(f"{study.scenario.name}: isolator designs, every isolator's stiffness and damping scaled")
    save_figure(fig, study.folder / "maps.png", dpi=110)


def scatter_designs(study: TradeoffStudy, ax: plt.Axes, x: np.ndarray, front: list[tuple[int, int]],
                    y: np.ndarray | None = None, ylabel: str | None = None, scale_at: Corner = "lower left") -> None:
    """Every design at (``x``, ``y``) (default: transmissibility at the reference frequency, log axis),
    coloured by damping and sized by stiffness (the size scale's legend at ``scale_at``); the front and the
    scenario's design."""
    y = study.transmissibility if y is None else y
    ok = np.isfinite(x) & np.isfinite(y)
    kk = np.broadcast_to(study.stiffness[:, None], ok.shape)
    cc = np.broadcast_to(study.damping[None, :], ok.shape)
    if ok.any():
        size = 14 + 30 * kk[ok] / kk.max()
        points = ax.scatter(x[ok], y[ok], c=cc[ok], s=size, cmap="viridis", norm=LogNorm(),
                            label="design (size: stiffness)")
        bar = ax.figure.colorbar(points, ax=ax, label="damping scale (x the scenario's) [-]")
        plain_log_axis(bar.ax.yaxis)
        ax.add_artist(_size_scale(ax, study.stiffness, scale_at))
    if front:
        ax.plot([x[p] for p in front], [y[p] for p in front], "-o", color="tab:red", ms=5,
                lw=1.5, label="Pareto front")
    nominal = study.nominal()
    if nominal is not None and ok[nominal]:
        ax.plot(x[nominal], y[nominal], "*", ms=18, mfc="tab:red", mec="black",
                label="scenario's design")
    ax.set_yscale("log")
    plain_log_axis(ax.yaxis)
    ax.set_ylabel(ylabel or f"floor-to-table transmissibility at {study.reference_hz:g} Hz, worst of x, y, z [m/m]")
    ax.grid(True, which="both", alpha=0.3)


def _size_scale(ax: plt.Axes, stiffness: np.ndarray, where: Corner) -> Legend:
    """The markers' size scale: a marker for the smallest, a middle and the largest stiffness factor, sized as
    :func:`scatter_designs` sizes them (area ``14 + 30 k / k_max`` points^2)."""
    factors = np.unique(np.asarray(stiffness, dtype=float))
    shown = sorted({float(factors[0]), float(factors[factors.size // 2]), float(factors[-1])})
    handles = [Line2D([], [], ls="", marker="o", color="0.55", markersize=float(np.sqrt(14 + 30 * k / factors[-1])),
                      label=f"x{k:.3g}") for k in shown]
    return ax.legend(handles=handles, title="stiffness scale\n(x the scenario's)", loc=where, fontsize=8,
                     title_fontsize=8, labelspacing=1.0)


def plot_tradeoff(study: TradeoffStudy) -> None:
    """``tradeoff.png``: the time figure against transmissibility, the Pareto front and the scenario's design."""
    fig, ax = plt.subplots(figsize=(9, 6), constrained_layout=True)
    scatter_designs(study, ax, study.settling_time, study.pareto())
    ax.set_xlabel("total time of the sequence [s]" if study.sequence else
                  f"largest settling time after the carriages stop [s] (band: {study.band.how()})")
    ax.set_title(f"{study.scenario.name}: {'total time' if study.sequence else 'settling'} against floor "
                 "isolation (lower left is better)")
    ax.legend(loc="upper right")
    save_figure(fig, study.folder / "tradeoff.png", dpi=110)


def plot_throughput(study: TradeoffStudy) -> None:
    """``throughput.png``: transmissibility against moves (or steps) per hour, with its own Pareto front."""
    fig, ax = plt.subplots(figsize=(9, 6), constrained_layout=True)
    scatter_designs(study, ax, study.per_hour, study.throughput_pareto(), scale_at="upper left")
    what = ("steps per hour of the sequence" if study.sequence else
            "moves per hour (move + window settling, repeated)")
    ax.set_xlabel(f"{what} [1/h]")
    ax.set_title(f"{study.scenario.name}: throughput against floor isolation (lower right is better)")
    ax.legend(loc="lower right")
    save_figure(fig, study.folder / "throughput.png", dpi=110)


def _header(study: TradeoffStudy) -> list[str]:
    time = "total time [s]" if study.sequence else "settling [s]"
    extra = (["steps per hour"] if study.sequence else ["window settling [s]", "moves per hour"]) \
        if study.has_throughput else []
    budget = [f"budget at {study.budget_point} [nm]"] if study.has_budget else []
    return table_header(["stiffness x", "damping x", time, *extra, f"transmissibility at {study.reference_hz:g} Hz",
                         "resonance peak", *budget])


def _row(study: TradeoffStudy, p: tuple[int, int]) -> str:
    extra = ""
    if study.has_throughput:
        rate = fmt(float(study.per_hour[p]), ".1f")
        extra = f" {rate} |" if study.sequence else f" {fmt(float(study.window_settling[p]), '.3f')} | {rate} |"
    budget = f" {fmt(float(study.budget_rms[p]) * 1e9, '.4g')} ({study.budget_axis[p]}) |" if study.has_budget else ""
    return (f"| {study.stiffness[p[0]]:.3g} | {study.damping[p[1]]:.3g} | {study.settling_time[p]:.3f} |{extra} "
            f"{study.transmissibility[p]:.3g} | {study.peak[p]:.3g} at {study.peak_hz[p]:.2f} Hz |{budget}")


def _method(study: TradeoffStudy) -> str:
    sc = study.scenario
    if study.sequence:
        return (f"Time: the total time of the scenario's `[sequence]` ({len(sc.sequence.steps) if sc.sequence else 0} "
                "steps, each starting once every window has held for the measurement), first step's start to last "
                "step's end, from the exact time-varying simulation (`run_sequence(..., parameters=p)`); "
                f"throughput in steps per hour. A sequence may take at most {study.duration:.4g} s.")
    text = (f"Settling: the largest settling time of the six table signals after the carriages stop, from the exact "
            f"time-varying simulation, band: {study.band.how()}.")
    if study.has_throughput:
        text += (" Throughput: a machine repeating the move and waiting after each until every `[[windows]]` "
                 "point holds its window makes 3600 / (move time + window settling time) moves per hour.")
    return text + (f" Transient runs of {study.duration:.3g} s (the scenario's {sc.simulation.duration:.3g} s, "
                   "lengthened when the least damped designs need longer to settle).")


def _against(study: TradeoffStudy, front: list[tuple[int, int]], nominal: tuple[int, int]) -> list[str]:
    t0, s0 = study.transmissibility[nominal], study.settling_time[nominal]
    what = "total time" if study.sequence else "settling"
    faster = [p for p in front if study.transmissibility[p] <= t0 * (1 + 1e-12)]
    quieter = [p for p in front if study.settling_time[p] <= s0 * (1 + 1e-12)]
    lines = ["", "## Against the scenario's design", ""]
    if faster:
        best = min(faster, key=lambda p: study.settling_time[p])
        lines.append(f"- Isolating at least as well: {what} {study.settling_time[best]:.3f} s instead of "
                     f"{s0:.3f} s with stiffness x{study.stiffness[best[0]]:.3g}, "
                     f"damping x{study.damping[best[1]]:.3g}.")
    if quieter:
        best = min(quieter, key=lambda p: study.transmissibility[p])
        lines.append(f"- {'Finishing' if study.sequence else 'Settling'} at least as fast: transmissibility "
                     f"{study.transmissibility[best]:.3g} instead of {t0:.3g} at {study.reference_hz:g} Hz with "
                     f"stiffness x{study.stiffness[best[0]]:.3g}, damping x{study.damping[best[1]]:.3g}.")
    if study.has_throughput and np.isfinite(study.per_hour[nominal]):
        rates = np.where(np.isfinite(study.per_hour), study.per_hour, -np.inf)
        at = int(np.argmax(rates))
        top = (at // rates.shape[1], at % rates.shape[1])
        lines.append(f"- Most {study.rate_label}: {study.per_hour[top]:.1f} instead of {study.per_hour[nominal]:.1f} "
                     f"with stiffness x{study.stiffness[top[0]]:.3g}, damping x{study.damping[top[1]]:.3g} "
                     f"(transmissibility {study.transmissibility[top]:.3g}).")
    return lines


def write_tradeoff_report(study: TradeoffStudy, budget: Sequence[str] = ()) -> None:
    """``report.md``: the method, the scenario's design, the Pareto-optimal designs (in time and in throughput),
    the ``budget`` section (:func:`studies.tradeoff_budget.budget_report`), the designs without numbers and the
    assumptions."""
    header = _header(study)
    sc = study.scenario
    lines = [f"# Isolation against {'throughput' if study.sequence else 'settling'}: {sc.name}", "",
             f"{study.stiffness.size} stiffness scales ({study.stiffness[0]:.3g} to {study.stiffness[-1]:.3g}) x "
             f"{study.damping.size} damping scales ({study.damping[0]:.3g} to {study.damping[-1]:.3g}), "
             "applied to every isolator on every axis, run as one `isolator.sweep`. " + _method(study) +
             " Transmissibility: floor motion to table motion at the mass centre, "
             "same axis, the worst of x, y and z, of the table linearised with its carriages at their start.",
             *pneumatic_note(sc), "", "![maps](maps.png)", "", "![tradeoff](tradeoff.png)", ""]
    if study.has_throughput:
        lines += ["![throughput](throughput.png)", ""]
    nominal = study.nominal()
    if nominal is not None and np.isfinite(study.settling_time[nominal]):
        lines += ["## The scenario's design", "", *header, _row(study, nominal), ""]
        own = study.design_band(*nominal)
        if own is not None:
            lines += [*band_lines(own, "Its band; each design has its own (the `band` column of `designs.csv`).",
                                  sc.name), ""]
    front = study.pareto()
    lines += ["## Pareto-optimal designs", "",
              f"No other design on the grid has a shorter {study.time_label} and isolates better at once.", "",
              *header]
    lines += [_row(study, p) for p in front] or ["| (none) | | | | |"]
    if study.sequence and study.has_throughput:
        lines += ["", f"The sequence's {len(study.scenario.sequence.steps) if study.scenario.sequence else 0} steps "
                  "per total time make its steps per hour, so the front in steps per hour (`throughput.png`) holds "
                  "the same designs."]
    elif study.has_throughput:
        lines += ["", f"## Pareto-optimal designs in {study.rate_label}", "",
                  f"No other design on the grid makes more {study.rate_label} and isolates better at once "
                  "(`throughput.png`), by decreasing throughput.", "", *header]
        lines += [_row(study, p) for p in study.throughput_pareto()] or ["| (none) | | | | |"]
    if nominal is not None and np.isfinite(study.settling_time[nominal]):
        lines += _against(study, front, nominal)
    lines += ["", *budget]
    lines += ["", "## Designs without numbers", ""]
    tips = study.stiffness[~study.stable]
    lines.append(f"- The table tips at stiffness x{', x'.join(f'{v:.3g}' for v in tips)} (rocking stiffness at or "
                 "below zero with the carriages at their start or end); no run." if tips.size else
                 "- Every stiffness on the grid stands.")
    lines += [f"- Stiffness x{study.stiffness[i]:.3g}, damping x{study.damping[j]:.3g}: {study.status[i, j]}: {why}"
              for (i, j), why in sorted(study.failures.items())]
    missing = int(np.sum(np.isnan(study.settling_time[study.stable]))) - len(study.failures)
    if missing:
        lines.append(f"- {missing} designs show no settling time within the run (lengthen `simulation.duration`).")
    lines += ["", "## Assumptions", "",
              "- All isolators scale together; the preload shares (the weight each carries) do not change, so "
              "softer isolators sag further but carry the same loads.",
              "- The transmissibility is that of the parked table (carriages at their start); it changes a "
              "little as the carriages travel (`isolator modes` shows how the modes move)."]
    if not study.sequence:
        lines.append(
            "- The settling band is the scenario's `[settling]` rule (default: 5 % of each signal's peak in "
            "that run), so each design is judged against its own peak, as in the paper: the sweep asks how "
            "fast each design's own transient dies out, and one baseline band would instead mostly measure "
            "the peak (a soft design moves further, so it could not even reach a stiff design's band). "
            "`designs.csv` gives each design's six half-widths in its `band` column (x=...,rz=..., m and "
            "rad), as `isolator simulate --band` takes them; a scaled design is "
            "`Simulator.run(p=sim.scaled_parameters(k, c), band=...)` (the command line has no scale option).")
    else:
        lines.append("- Each step is judged by the scenario's windows (absolute, at the points), not by a 5 % band; "
                     "a scaled design is `run_sequence(scenario, parameters=Simulator(scenario)"
                     ".scaled_parameters(k, c))`.")
    lines.append(f"- Full numbers: `designs.csv`; re-run: `isolator study tradeoff {sc.name} --out DIR`.")
    write_report(study.folder, lines)


check_public(globals())
