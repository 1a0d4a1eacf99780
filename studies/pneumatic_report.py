"""What the pneumatic design study (:mod:`studies.pneumatic`) writes: ``maps.png``, ``pareto.png``,
``designs.csv`` and ``report.md``."""

from __future__ import annotations

import csv

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.patches import Patch
from matplotlib.patheffects import Normal, Stroke
from matplotlib.ticker import LogLocator

from isolator import Band
from isolator.scenario.arguments import check_public
from isolator.scenario.output_files import atomic_output

from .figures import log_mesh_edges, plain_log_axis, save_figure
from .pneumatic_results import MIN_WINDOW, PneumaticStudy, Transients
from .reporting import band_cell, fmt, table_header, table_row, write_report

__all__ = ["write_outputs"]

#: ticks of the diameter axes per decade (the grids span less than one)
_DIAMETER_TICKS = (1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0)


def write_outputs(study: PneumaticStudy) -> None:
    """``maps.png``, ``pareto.png``, ``designs.csv`` and ``report.md`` in ``study.folder``."""
    _plot_maps(study)
    _plot_pareto(study)
    _write_csv(study)
    _write_report(study)


def _plot_maps(study: PneumaticStudy) -> None:
    mm = 1e3
    panels = [
        (study.heave_peak, "heave (z) transmissibility peak [m/m]", "magma", LogNorm()),
        (study.rocking_peak, "rocking transmissibility peak, worst of rx, ry [rad/rad]", "magma", LogNorm()),
        (study.settling_time, "5 % settling time about the leveling table [s]", "viridis", LogNorm()),
        (study.leveling_time, "leveling time after the stop, slowest valve group [s]", "viridis", LogNorm()),
    ]
    fig, axes = plt.subplots(2, 2, figsize=(14, 11), constrained_layout=True)
    ne, de = log_mesh_edges(study.ratios), log_mesh_edges(study.diameters * mm)
    closed = np.array([c.diameter for c in study.closed_form]) * mm
    for ax, (values, label, cmap, norm) in zip(axes.ravel(), panels, strict=True):
        ax.set_facecolor("0.88")
        if np.isfinite(values).any():
            mesh = ax.pcolormesh(ne, de, np.ma.masked_invalid(values), cmap=cmap, norm=norm, shading="flat")
            bar = fig.colorbar(mesh, ax=ax, label=label)
            if norm is not None:
                plain_log_axis(bar.ax.yaxis)
        elif not study.moves:
            ax.text(0.5, 0.2, "no carriage moves: no runs", transform=ax.transAxes, ha="center", va="center")
        ax.plot(study.ratios, study.optimal_diameter * mm, "-o", color="white", mec="black", ms=4, lw=2,
                path_effects=[Stroke(linewidth=3.5, foreground="black"), Normal()],
                label="optimal orifice (least heave peak)")
        ax.plot(study.ratios, closed, "--", color="tab:cyan", lw=1.5, label="closed form, one-mass isolator")
        front = study.pareto()
        if front:
            ax.plot([study.ratios[j] for _, j in front], [study.diameters[i] * mm for i, _ in front], "s", ms=5,
                    mfc="none", mec="tab:red", mew=1.2, label="Pareto-optimal (settling vs isolation)")
        ax.plot(study.own_ratio, study.own_diameter * mm, "*", ms=15, mfc="tab:red", mec="white",
                label="scenario's design")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(ne[0], ne[-1])
        ax.set_ylim(de[0], de[-1])
        plain_log_axis(ax.xaxis)
        plain_log_axis(ax.yaxis)
        ax.yaxis.set_major_locator(LogLocator(subs=_DIAMETER_TICKS))
        ax.set_xlabel("damping-chamber volume ratio N = V2 / V1r [-]")
        ax.set_ylabel("orifice diameter, every isolator [mm]")
        ax.set_title(label.split(" [")[0])
    handles = axes[0, 0].get_legend_handles_labels()[0]
    handles.append(Patch(facecolor="0.88", edgecolor="0.6",
                         label="no value (table tips, run diverged, not settled or not level by the end of the run)"))
    fig.legend(handles=handles, loc="outside lower center", ncol=3, fontsize=9)
    fig.suptitle(f"{study.scenario.name}: every isolator's orifice and damping chamber", fontsize=13)
    save_figure(fig, study.folder / "maps.png", dpi=100)


def _plot_pareto(study: PneumaticStudy) -> None:
    fig, ax = plt.subplots(figsize=(9.5, 6.5), constrained_layout=True)
    settle, trans = study.settling_time, study.transmissibility
    ok = np.isfinite(settle) & np.isfinite(trans)
    dd = np.broadcast_to(study.diameters[:, None], ok.shape) * 1e3
    nn = np.broadcast_to(study.ratios[None, :], ok.shape)
    if ok.any():
        size = 12 + 40 * (dd[ok] - dd.min()) / max(float(np.ptp(dd)), 1e-12)
        points = ax.scatter(settle[ok], trans[ok], c=nn[ok], s=size, cmap="viridis", norm=LogNorm(),
                            label="design (size: orifice diameter)")
        bar = fig.colorbar(points, ax=ax, label="damping-chamber volume ratio N = V2 / V1r [-]")
        plain_log_axis(bar.ax.yaxis)
    front = study.pareto()
    if front:
        ax.plot([settle[p] for p in front], [trans[p] for p in front], "-o", color="tab:red", ms=5, lw=1.5,
                label="Pareto front")
    own = study.own_runs.settling[0, 0]
    if np.isfinite(own):
        ax.plot(own, study.own_linear["at_ref"], "*", ms=18, mfc="tab:red", mec="black", label="scenario's design")
    ax.set_xscale("log")
    ax.set_yscale("log")
    plain_log_axis(ax.xaxis)
    plain_log_axis(ax.yaxis)
    ax.set_xlabel("5 % settling time about the leveling table, after the carriages stop [s]")
    ax.set_ylabel(f"floor-to-table transmissibility at {study.reference_hz:g} Hz, worst of x, y, z [m/m]")
    ax.set_title(f"{study.scenario.name}: settling against floor isolation (lower left is better)")
    ax.grid(True, which="both", alpha=0.3)
    if ok.any() or front:
        ax.legend(loc="center right")
    save_figure(fig, study.folder / "pareto.png", dpi=110)


def _status(study: PneumaticStudy, ij: tuple[int, int]) -> str:
    if ij in study.tips:
        return "tips"
    return study.runs.status(ij) if study.moves else "no moves"


def _write_csv(study: PneumaticStudy) -> None:
    runs = study.runs
    rule = Band.from_settling(study.scenario.settling)
    windows = bool(study.scenario.windows)
    with atomic_output(study.folder / "designs.csv", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["orifice_diameter_m", "volume_ratio", "heave_peak", "heave_peak_hz", "rocking_peak",
                         "rocking_peak_hz", f"transmissibility_at_{study.reference_hz:g}_hz",
                         "dynamic_settling_time_s", "contract_settling_time_s", "band", "leveling_time_s",
                         *(["window_settling_time_s", "moves_per_hour"] if windows else []),
                         "run_duration_s", "status"])
        for i, d in enumerate(study.diameters):
            for j, n in enumerate(study.ratios):
                values = (study.heave_peak, study.heave_peak_hz, study.rocking_peak, study.rocking_peak_hz,
                          study.transmissibility, runs.settling, runs.contract_settling)
                throughput = [f"{runs.window[i, j]:.6g}", f"{runs.per_hour[i, j]:.6g}"] if windows else []
                writer.writerow([f"{d:.6g}", f"{n:.6g}", *(f"{v[i, j]:.6g}" for v in values),
                                 band_cell(rule, runs.band[i, j]), f"{runs.leveling[i, j]:.6g}", *throughput,
                                 f"{runs.duration[i, j]:.6g}", _status(study, (i, j))])


_DESIGN_COLUMNS = ["orifice [mm]", "N", "settling, dynamic [s]", "settling, contract [s]", "leveling [s]",
                   "transmissibility at {f:g} Hz", "heave peak", "rocking peak"]
#: with ``[[windows]]``, after the leveling time
_WINDOW_COLUMNS = ["window settling [s]", "moves per hour"]


def _design_row(d: float, n: float, runs: Transients, ij: tuple[int, int], linear: dict[str, float],
                windows: bool = False) -> str:
    throughput = [fmt(runs.window[ij], ".3f"), fmt(runs.per_hour[ij], ".1f")] if windows else []
    return table_row([f"{d * 1e3:.3g}", f"{n:.3g}", fmt(runs.settling[ij], ".3f"),
                      fmt(runs.contract_settling[ij], ".3f"), fmt(runs.leveling[ij], ".3f"), *throughput,
                      fmt(linear["at_ref"]), f"{linear['heave']:.3f} at {linear['heave_hz']:.2f} Hz",
                      f"{linear['rocking']:.3f} at {linear['rocking_hz']:.2f} Hz"])


def _grid_linear(study: PneumaticStudy, ij: tuple[int, int]) -> dict[str, float]:
    return {"at_ref": study.transmissibility[ij], "heave": study.heave_peak[ij], "heave_hz": study.heave_peak_hz[ij],
            "rocking": study.rocking_peak[ij], "rocking_hz": study.rocking_peak_hz[ij]}


def _throughput_lines(study: PneumaticStudy) -> list[str]:
    """With ``[[windows]]``: what the window settling and moves per hour are, and the design that makes most."""
    if not study.scenario.windows:
        return []
    lines = ["", "Throughput: each run's window settling time (after the stop, until every `[[windows]]` point "
             "holds its window) and the moves per hour of a machine repeating the move and waiting for the "
             "windows, 3600 / (move time + window settling time)."]
    rates = study.runs.per_hour
    if np.any(np.isfinite(rates)):
        at = int(np.nanargmax(rates))
        i, j = at // rates.shape[1], at % rates.shape[1]
        lines[-1] += (f" Most moves per hour on the grid: {rates[i, j]:.1f} with orifice "
                      f"{study.diameters[i] * 1e3:.3g} mm, N = {study.ratios[j]:.3g} (the scenario's own: "
                      f"{fmt(study.own_runs.per_hour[0, 0], '.1f')}).")
    return lines


def _write_report(study: PneumaticStudy) -> None:
    sc, d, n = study.scenario, study.diameters, study.ratios
    windows = bool(sc.windows)
    columns = [c.format(f=study.reference_hz) for c in _DESIGN_COLUMNS]
    if windows:
        columns[5:5] = _WINDOW_COLUMNS
    durations = np.unique(study.runs.duration[np.isfinite(study.runs.duration)])
    lengths = f" (run lengths used: {', '.join(f'{v:.3g} s' for v in durations)})" if durations.size else ""
    lines = [f"# Air-spring orifice and damping chamber: {sc.name}", "",
             f"{d.size} orifice diameters ({d[0] * 1e3:.3g} to {d[-1] * 1e3:.3g} mm, log-spaced) x {n.size} "
             f"damping-chamber volume ratios N = V2 / V1r ({n[0]:.3g} to {n[-1]:.3g}), each applied to every "
             f"isolator (damping chamber = N x its spring chamber). The scenario's own design: orifice "
             f"{study.own_diameter * 1e3:.3g} mm, N = {study.own_ratio:.3g}.", *_throughput_lines(study), "",
             "![maps](maps.png)", "", "![pareto](pareto.png)", ""]
    lines += ["## The scenario's design", "", *table_header(columns),
              _design_row(study.own_diameter, study.own_ratio, study.own_runs, (0, 0), study.own_linear, windows), ""]
    lines += ["## Optimal orifice per volume ratio", "",
              "The orifice that minimises the table's heave transmissibility peak, refined beyond the grid by a "
              "bounded minimisation in log diameter (linearised table). Beside it the optimum of a one-mass "
              "relaxation (Zener) isolator, Ruzicka and Derby: the peak 1 + 2/N, at the fixed point "
              "w*^2 = 2 k0 (N + 1) / (m (N + 2)) where every relaxation time gives the same |T|, reached when "
              "w* tau = sqrt(1 + N), i.e. tau = sqrt(m (N + 2) / (2 k0)) (m: the table's whole mass, k0 = "
              "sum n p0 A^2 / (V1r + V2): the isolators' static stiffness). tau: the geometric mean over the "
              "isolators of V2 / (n G p0), G = pi d^4 / (128 mu L).", "",
              *table_header(["N", "optimal orifice [mm]", "heave peak", "1 + 2/N", "peak / (1 + 2/N)", "at [Hz]",
                             "fixed point [Hz]", "tau [ms]", "closed-form tau [ms]", "closed-form orifice [mm]"])]
    for o, c in zip(study.optima, study.closed_form, strict=True):
        edge = " (search bound)" if o.at_edge else ""
        lines.append(table_row([f"{o.ratio:.3g}", fmt(o.diameter * 1e3, ".4g") + edge, fmt(o.peak, ".4f"),
                                f"{c.peak:.4f}", fmt(o.peak / c.peak, ".4f"), fmt(o.frequency_hz, ".3f"),
                                f"{c.frequency_hz:.3f}", fmt(o.relaxation_time * 1e3, ".4g"),
                                f"{c.relaxation_time * 1e3:.4g}", f"{c.diameter * 1e3:.4g}"]))
    lines += ["", "Larger damping chambers lower the best achievable heave peak (1 + 2/N); the optimal orifice "
              "changes little with N. Too small an orifice shuts the damping chamber off (the stiff spring "
              "chamber alone resonates), too large a one joins the chambers freely (the soft spring resonates); "
              "in between the air flowing through the orifice damps.", ""]
    front = study.pareto()
    lines += ["## Pareto-optimal designs", "",
              f"No other design on the grid settles faster and isolates better at {study.reference_hz:g} Hz at once.",
              "", *table_header(columns)]
    lines += [_design_row(d[i], n[j], study.runs, (i, j), _grid_linear(study, (i, j)), windows) for i, j in front]
    if not front:
        lines.append(table_row(["(none)"] + [""] * (len(columns) - 1)))
    lines += ["", "## Designs without numbers", ""]
    counts: dict[str, int] = {}
    for i in range(d.size):
        for j in range(n.size):
            status = _status(study, (i, j))
            if status != "ok":
                counts[status] = counts.get(status, 0) + 1
    lines += [f"- {status}: {count} design{'' if count == 1 else 's'} (see `designs.csv`)"
              for status, count in sorted(counts.items())]
    lines += [f"- Diverged: d = {d[i] * 1e3:.3g} mm, N = {n[j]:.3g}: {why}"
              for (i, j), why in sorted(study.runs.failures.items())]
    if not counts:
        lines.append("- None: every design settled and leveled within its run.")
    lines += ["", "## Assumptions", "",
              "- Settling: the study's figure is the 5 % settling time of the motion about the slowly leveling "
              "table (`Response.pneumatic.dynamic_settling_time_max`: the table's signals minus the quasi-static "
              "pose its current air holds), largest of the six signals. The contract's settling time about the "
              "final level equilibrium (`settling_time_max`) is in the tables and `designs.csv` too; it mostly "
              "measures how fast the valves re-level, which the orifice barely changes.",
              "- Settling band: the scenario's `[settling]` rule, by default 5 % of each signal's own peak in that "
              "design's run, as in the paper, for both settling times: the sweep asks how fast each design's own "
              "motion dies out, and the orifice and chamber change the peak a lot (one baseline band would "
              "mostly measure the peak). `designs.csv` gives each design's six half-widths in its `band` column "
              "(x=...,rz=..., m and rad, as `isolator simulate --band` takes them); a design is "
              "`Simulator.run(p=..., band=...)` with its parameters (the command line has no orifice option).",
              "- The contract's settling time has no value where the table comes to rest outside its 5 % band: the "
              "valves stop inside their dead band, which can leave the table tilted by more than 5 % of a small "
              "rocking peak. `designs.csv` lists it as NaN with the status `ok` when the study's figures are there.",
              "- Leveling time: after the stop, from when every valve group's sensor stays within 1.1 dead bands; "
              "the largest over the groups; no value when a group is not level by the end of the run.",
              "- Transmissibility: the table parked with its carriages at their start, linearised about rest with "
              "the valves closed (their dead zone) and the chamber pressures as states; floor motion to table "
              "motion at the mass centre, same axis.",
              f"- Runs: the scenario's moves, at least {MIN_WINDOW:g} s after the carriages stop (or the scenario's "
              "duration if longer); designs not settled or not level by then run again, longer, unless their "
              "valves ran out of supply pressure" + lengths + ".",
              "- The spring chambers, pistons, capillary lengths, valves and lines stay the scenario's; only the "
              "orifice diameter and the damping-chamber volume change.",
              f"- Full numbers: `designs.csv`; re-run: `isolator study pneumatic {sc.name} --out DIR`."]
    if not study.moves:
        lines.insert(8, "No carriage moves in this scenario: no runs, so no settling or leveling times; the "
                        "transmissibility and the optimal orifices only.\n")
    write_report(study.folder, lines)


check_public(globals())
