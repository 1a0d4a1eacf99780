"""Floor isolation against settling: every isolator's stiffness and damping swept together.

Run it with ``isolator study tradeoff [SCENARIO] --out DIR``. Each design scales
the stiffness and the damping of every isolator (all axes) by two factors on
log grids; the scenario's own design is 1 x 1. For each design the study
measures

* the largest 5 % settling time of the scenario's carriage moves, from the
  exact time-varying simulation (one batch of transient runs);
* the floor-to-table transmissibility of the table parked with the carriages
  at their start (linearised): the worst of the x, y and z same-axis values at
  a reference frequency (default 10 Hz: how much floor vibration gets through)
  and the worst resonance peak (how much the table amplifies near its modes).

Soft isolators isolate better and settle slower; damping shortens settling and
lowers the resonance peak but lets more high-frequency floor motion through.
The study writes

* ``maps.png``: settling time, transmissibility at the reference frequency and
  resonance peak over the (stiffness, damping) grid, tipping designs hatched;
* ``tradeoff.png``: settling time against transmissibility for every design,
  with the Pareto front and the scenario's design;
* ``designs.csv``: every design's numbers;
* ``report.md``: the scenario's design, the Pareto-optimal designs, the best
  design at the scenario's transmissibility and at its settling time, and the
  assumptions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import LogNorm

from isolator import Band, ParameterError, Scenario, ScenarioError, Simulator, UnstableTableError
from isolator.analysis.linear import linearise
from isolator.analysis.transmissibility import transmissibility

from .figures import log_mesh_edges, plain_log_axis, save_figure
from .reporting import band_lines, design_band, output_folder, progress_printer, table_header, write_report
from .tradeoff_designs import write_designs_csv
from .tradeoff_pneumatic import pneumatic_note, pneumatic_settling

__all__ = ["TradeoffStudy", "pareto_front", "run_tradeoff_study"]

#: default grids of scale factors on every isolator's stiffness and damping
STIFFNESS_SCALES = np.geomspace(0.25, 4.0, 17)
DAMPING_SCALES = np.geomspace(0.25, 8.0, 16)
_AXES = ("x", "y", "z")
#: longest time after the stop the runs are lengthened to [s]
MAX_WINDOW = 60.0


@dataclass(frozen=True)
class TradeoffStudy:
    """Every design's settling time and transmissibility.

    Attributes
    ----------
    scenario : Scenario
    stiffness, damping : ndarray (nk,), (nc,)
        Scale factors on every isolator's stiffness and damping.
    reference_hz : float
        Frequency of the transmissibility figure [Hz].
    settling_time : ndarray (nk, nc)
        Largest settling time [s] in ``band``; NaN where a design tips, diverges or shows none.
    transmissibility : ndarray (nk, nc)
        Worst same-axis floor-to-table transmissibility of x, y, z at ``reference_hz`` [m/m].
    peak : ndarray (nk, nc)
        Worst same-axis resonance peak of x, y, z [m/m].
    peak_hz : ndarray (nk, nc)
        Its frequency [Hz].
    stable : ndarray (nk,) of bool
        False where the table tips at that stiffness (whatever the damping).
    duration : float
        Length of the transient runs [s] (the scenario's, or longer so that the least
        damped designs settle).
    failures : dict
        ``(i, j) -> reason`` for designs whose transient run diverged.
    folder : Path
        Where the figures and the report are.
    band : Band
        The band rule: the scenario's ``[settling]`` (each design its own 5 %, as the paper).
    half_widths : ndarray (nk, nc, 6)
        The band each design's settling time is measured in [m, rad] (NaN: no run); :meth:`design_band`.
    """

    scenario: Scenario
    stiffness: np.ndarray
    damping: np.ndarray
    reference_hz: float
    settling_time: np.ndarray
    transmissibility: np.ndarray
    peak: np.ndarray
    peak_hz: np.ndarray
    stable: np.ndarray
    duration: float
    failures: dict[tuple[int, int], str] = field(default_factory=dict)
    folder: Path = Path(".")
    band: Band = field(default_factory=Band)
    half_widths: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 6)))

    def design_band(self, i: int, j: int) -> Band | None:
        """Design (i, j)'s band, resolved (None: no run)."""
        return design_band(self.band, self.half_widths[i, j])

    def pareto(self) -> list[tuple[int, int]]:
        """The designs no other design beats in both settling time and transmissibility,
        by increasing settling time."""
        points = np.column_stack([self.settling_time.ravel(), self.transmissibility.ravel()])
        front = pareto_front(points)
        nc = self.damping.size
        return [(int(i) // nc, int(i) % nc) for i in front]

    def nominal(self) -> tuple[int, int] | None:
        """Grid indices of the scenario's own design (scales 1 x 1), if on the grid."""
        i = np.flatnonzero(np.isclose(self.stiffness, 1.0, rtol=1e-9))
        j = np.flatnonzero(np.isclose(self.damping, 1.0, rtol=1e-9))
        return (int(i[0]), int(j[0])) if i.size and j.size else None


def pareto_front(points: np.ndarray) -> np.ndarray:
    """Indices of the rows of ``points`` (n, 2) not dominated by another row (both objectives
    minimised; rows with NaN take no part), sorted by the first objective.

    A row is dominated when another is no worse in both objectives and better in one.
    """
    points = np.asarray(points, dtype=float)
    valid = np.flatnonzero(np.all(np.isfinite(points), axis=1))
    order = valid[np.lexsort((points[valid, 1], points[valid, 0]))]
    front: list[int] = []
    best = math.inf
    for i in order:  # increasing first objective: kept when it improves the second
        if points[i, 1] < best:
            front.append(int(i))
            best = points[i, 1]
    return np.array(front, dtype=int)


def run_tradeoff_study(
    folder: str | Path,
    scenario: Scenario,
    stiffness: Sequence[float] | np.ndarray | None = None,
    damping: Sequence[float] | np.ndarray | None = None,
    reference_hz: float = 10.0,
    progress: bool = True,
) -> TradeoffStudy:
    """Sweep the isolators' stiffness and damping; write figures, ``designs.csv`` and ``report.md``.

    Parameters
    ----------
    folder : str or Path
    scenario : Scenario
        With carriage moves that stop (a sine never settles).
    stiffness, damping : ndarray, optional
        Scale factors (> 0), increasing; default :data:`STIFFNESS_SCALES`, :data:`DAMPING_SCALES`.
    reference_hz : float
        Frequency of the transmissibility figure [Hz], > 0.
    progress : bool
        Print a line per stage.

    Raises
    ------
    ParameterError
        Bad scales or frequency.
    ScenarioError
        No carriages, or carriages that never stop.
    """
    k = _grid(STIFFNESS_SCALES if stiffness is None else stiffness, "stiffness")
    c = _grid(DAMPING_SCALES if damping is None else damping, "damping")
    if not (math.isfinite(reference_hz) and reference_hz > 0):
        raise ParameterError(f"reference_hz: must be a finite frequency > 0, got {reference_hz}")
    sim = Simulator(scenario)
    if not scenario.carriages:
        raise ScenarioError("carriages: none move, so there is no settling time to trade")
    if not math.isfinite(sim.stop_time):
        raise ScenarioError("carriages: the moves never stop (a sine), so there is no settling time to trade")
    out = output_folder(folder)
    say = progress_printer(progress)
    say(f"tradeoff: {k.size} x {c.size} designs of {scenario.name}; which stiffnesses tip ...")
    stable = np.array([_stands(sim, scale) for scale in k])
    n_runs = int(stable.sum()) * c.size
    say(f"transmissibility of the {n_runs} designs that stand ...")
    trans, peak, peak_hz, decay = (np.full((k.size, c.size), np.nan) for _ in range(4))
    done = 0
    for i in np.flatnonzero(stable):
        for j in range(c.size):
            trans[i, j], peak[i, j], peak_hz[i, j], decay[i, j] = _linear_figures(sim, k[i], c[j], reference_hz)
            done += 1
            if n_runs >= 10 and done % max(1, n_runs // 10) == 0:
                say(f"  transmissibility: {done}/{n_runs} designs")
    # long enough after the stop for the slowest-decaying design to settle (5 % of an amplitude
    # no larger than the peak: ln 20 / decay rate, with a margin)
    window = scenario.simulation.duration - sim.stop_time
    if n_runs:
        needed = 2.5 * math.log(20.0) / max(float(np.nanmin(decay)), 1e-9)
        window = max(window, min(needed, MAX_WINDOW))
    duration = sim.stop_time + window
    if duration > scenario.simulation.duration * (1 + 1e-12):
        say(f"runs lengthened to {duration:.3g} s so that the least damped designs can settle")
        sim = Simulator(replace(scenario, simulation=replace(scenario.simulation, duration=duration)))
    settling = np.full((k.size, c.size), np.nan)
    band = Band.from_settling(scenario.settling)
    widths = np.full((k.size, c.size, 6), np.nan)
    failures: dict[tuple[int, int], str] = {}
    if n_runs:
        say(f"transient runs of the {n_runs} designs that stand ...")
        kk, cc = np.meshgrid(k[stable], c, indexing="ij")
        if scenario.is_pneumatic:  # one run each, settling about the leveling table
            values, failed, half = pneumatic_settling(sim, kk.ravel(), cc.ravel(), say, band)
        else:
            batch = sim.run_batch(kk.ravel(), cc.ravel(), progress=progress, diverged="record", band=band)
            values, failed, half = batch.settling_time_max, dict(batch.failures), batch.half_widths
        settling[stable] = values.reshape(kk.shape)
        widths[stable] = half.reshape(*kk.shape, 6)
        rows = np.flatnonzero(stable)
        failures = {(int(rows[r // c.size]), r % c.size): why for r, why in failed.items()}
    study = TradeoffStudy(scenario, k, c, reference_hz, settling, trans, peak, peak_hz, stable, duration, failures, out,
                          band, widths)
    _plot_maps(study)
    _plot_tradeoff(study)
    write_designs_csv(study)
    _write_report(study)
    return study


def _grid(values: Sequence[float] | np.ndarray, name: str) -> np.ndarray:
    grid = np.atleast_1d(np.asarray(values, dtype=float))
    if grid.ndim != 1 or grid.size < 2:
        raise ParameterError(f"{name}: give at least two scale factors")
    if not np.all(np.isfinite(grid)) or np.any(grid <= 0) or np.any(np.diff(grid) <= 0):
        raise ParameterError(f"{name}: scale factors must be finite, > 0 and increasing")
    return grid


def _stands(sim: Simulator, stiffness: float) -> bool:
    """Whether the table stands with its carriages at their start and at their end (statics do not
    depend on damping)."""
    try:
        sim.equilibria(sim.scaled_parameters(stiffness, 1.0))
    except UnstableTableError:
        return False
    return True


def _linear_figures(sim: Simulator, stiffness: float, damping: float, reference_hz: float) -> tuple[float, ...]:
    """Worst x, y, z same-axis transmissibility at ``reference_hz``, worst resonance peak, its frequency
    [Hz], and the slowest mode's decay rate [1/s]."""
    lin = linearise(sim.scenario, parameters=sim.scaled_parameters(stiffness, damping))
    at = lin.frequency_response(np.array([reference_hz]), [f"ground:{a}" for a in _AXES], list(_AXES))[0]
    response = transmissibility(lin)
    peaks = [response.peak(a) for a in _AXES]
    worst = max(range(len(_AXES)), key=lambda n: peaks[n][0])
    decay = float(-np.max(lin.eigenvalues.real))
    return float(np.max(np.abs(np.diag(at)))), peaks[worst][0], peaks[worst][1], decay


def _plot_maps(study: TradeoffStudy) -> None:
    panels = [
        (study.settling_time, f"largest settling time [s]\n(band: {study.band.how()})", "viridis", None),
        (study.transmissibility, f"transmissibility at {study.reference_hz:g} Hz [m/m], worst of x, y, z",
         "magma", LogNorm()),
        (study.peak, "resonance peak of the transmissibility [m/m], worst of x, y, z", "magma", LogNorm()),
    ]
    fig, axes = plt.subplots(1, 3, figsize=(17, 5.2), constrained_layout=True)
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


def _plot_tradeoff(study: TradeoffStudy) -> None:
    fig, ax = plt.subplots(figsize=(9, 6), constrained_layout=True)
    ok = np.isfinite(study.settling_time) & np.isfinite(study.transmissibility)
    kk = np.broadcast_to(study.stiffness[:, None], ok.shape)
    cc = np.broadcast_to(study.damping[None, :], ok.shape)
    if ok.any():
        size = 14 + 30 * kk[ok] / kk.max()
        points = ax.scatter(study.settling_time[ok], study.transmissibility[ok], c=cc[ok], s=size,
                            cmap="viridis", norm=LogNorm(), label="design (size: stiffness)")
        bar = fig.colorbar(points, ax=ax, label="damping scale (x the scenario's) [-]")
        plain_log_axis(bar.ax.yaxis)
    front = study.pareto()
    if front:
        ax.plot([study.settling_time[p] for p in front], [study.transmissibility[p] for p in front], "-o",
                color="tab:red", ms=5, lw=1.5, label="Pareto front")
    nominal = study.nominal()
    if nominal is not None and ok[nominal]:
        ax.plot(study.settling_time[nominal], study.transmissibility[nominal], "*", ms=18, mfc="tab:red",
                mec="black", label="scenario's design")
    ax.set_yscale("log")
    plain_log_axis(ax.yaxis)
    ax.set_xlabel(f"largest settling time after the carriages stop [s] (band: {study.band.how()})")
    ax.set_ylabel(f"floor-to-table transmissibility at {study.reference_hz:g} Hz, worst of x, y, z [m/m]")
    ax.set_title(f"{study.scenario.name}: settling against floor isolation (lower left is better)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper right")
    save_figure(fig, study.folder / "tradeoff.png", dpi=110)


def _row(study: TradeoffStudy, p: tuple[int, int]) -> str:
    return (f"| {study.stiffness[p[0]]:.3g} | {study.damping[p[1]]:.3g} | {study.settling_time[p]:.3f} | "
            f"{study.transmissibility[p]:.3g} | {study.peak[p]:.3g} at {study.peak_hz[p]:.2f} Hz |")


def _write_report(study: TradeoffStudy) -> None:
    header = table_header(["stiffness x", "damping x", "settling [s]",
                           f"transmissibility at {study.reference_hz:g} Hz", "resonance peak"])
    sc = study.scenario
    band_how = study.band.how()
    lines = [f"# Isolation against settling: {sc.name}", "",
             f"{study.stiffness.size} stiffness scales ({study.stiffness[0]:.3g} to {study.stiffness[-1]:.3g}) x "
             f"{study.damping.size} damping scales ({study.damping[0]:.3g} to {study.damping[-1]:.3g}), "
             "applied to every isolator on every axis. Settling: the largest settling time of the six "
             f"table signals after the carriages stop, from the exact time-varying simulation, band: {band_how}. "
             "Transmissibility: floor motion to table motion at the mass centre, "
             "same axis, the worst of x, y and z, of the table linearised with its carriages at their start. "
             f"Transient runs of {study.duration:.3g} s (the scenario's {sc.simulation.duration:.3g} s, lengthened "
             "when the least damped designs need longer to settle).", *pneumatic_note(sc), "",
             "![maps](maps.png)", "", "![tradeoff](tradeoff.png)", ""]
    nominal = study.nominal()
    if nominal is not None and np.isfinite(study.settling_time[nominal]):
        lines += ["## The scenario's design", "", *header, _row(study, nominal), ""]
        own = study.design_band(*nominal)
        if own is not None:
            lines += [*band_lines(own, "Its band; each design has its own (the `band` column of `designs.csv`).",
                                  sc.name), ""]
    front = study.pareto()
    lines += ["## Pareto-optimal designs", "",
              "No other design on the grid settles faster and isolates better at once.", "", *header]
    lines += [_row(study, p) for p in front] or ["| (none) | | | | |"]
    if nominal is not None and np.isfinite(study.settling_time[nominal]):
        t0, s0 = study.transmissibility[nominal], study.settling_time[nominal]
        faster = [p for p in front if study.transmissibility[p] <= t0 * (1 + 1e-12)]
        quieter = [p for p in front if study.settling_time[p] <= s0 * (1 + 1e-12)]
        lines += ["", "## Against the scenario's design", ""]
        if faster:
            best = min(faster, key=lambda p: study.settling_time[p])
            lines.append(f"- Isolating at least as well: settling {study.settling_time[best]:.3f} s instead of "
                         f"{s0:.3f} s with stiffness x{study.stiffness[best[0]]:.3g}, "
                         f"damping x{study.damping[best[1]]:.3g}.")
        if quieter:
            best = min(quieter, key=lambda p: study.transmissibility[p])
            lines.append(f"- Settling at least as fast: transmissibility {study.transmissibility[best]:.3g} "
                         f"instead of {t0:.3g} at {study.reference_hz:g} Hz with stiffness "
                         f"x{study.stiffness[best[0]]:.3g}, damping x{study.damping[best[1]]:.3g}.")
    lines += ["", "## Designs without numbers", ""]
    tips = study.stiffness[~study.stable]
    lines.append(f"- The table tips at stiffness x{', x'.join(f'{v:.3g}' for v in tips)} (rocking stiffness at or "
                 "below zero with the carriages at their start or end); no run." if tips.size else
                 "- Every stiffness on the grid stands.")
    lines += [f"- Diverged: {why}" for _, why in sorted(study.failures.items())]
    missing = int(np.sum(np.isnan(study.settling_time[study.stable]))) - len(study.failures)
    if missing:
        lines.append(f"- {missing} designs show no settling time within the run (lengthen `simulation.duration`).")
    lines += ["", "## Assumptions", "",
              "- All isolators scale together; the preload shares (the weight each carries) do not change, so "
              "softer isolators sag further but carry the same loads.",
              "- The transmissibility is that of the parked table (carriages at their start); it changes a "
              "little as the carriages travel (`isolator modes` shows how the modes move).",
              "- The settling band is the scenario's `[settling]` rule (default: 5 % of each signal's peak in "
              "that run), so each design is judged against its own peak, as in the paper: the sweep asks how "
              "fast each design's own transient dies out, and one baseline band would instead mostly measure "
              "the peak (a soft design moves further, so it could not even reach a stiff design's band). "
              "`designs.csv` gives each design's six half-widths in its `band` column (x=...,rz=..., m and "
              "rad), as `isolator simulate --band` takes them; a scaled design is "
              "`Simulator.run(p=sim.scaled_parameters(k, c), band=...)` (the command line has no scale option).",
              f"- Full numbers: `designs.csv`; re-run: `isolator study tradeoff {sc.name} --out DIR`."]
    write_report(study.folder, lines)
