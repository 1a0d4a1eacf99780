"""How the stage should move: the paper's profile, input shapers, time-optimal and optimised moves.

Run it with ``isolator study profiles [SCENARIO] --out DIR``. Every method is
judged by the true simulation, all in one band: 5 % of the paper profile's
peaks (kind ``baseline``), so that a method is not rewarded for a settling
time measured in a narrower band of its own:

* ``profiles.png``: each carriage's speed and acceleration per method;
* ``response.png``: the table's six signals after the stop, paper profile
  against the optimised ones (settling-time and cycle-time objectives);
* ``times.png``: move, settling and cycle time per method;
* ``robustness.png``: settling time per method on the model variants
  (isolator stiffness, damping, payload mass 15 % off);
* ``results.json``: per method its move, settling and cycle times and the
  ``band`` (six half-widths, m and rad); ``scenarios/<method>.toml``, the
  scenario of each method a scenario file can hold (the paper's, the
  optimised S-curves), for ``isolator simulate ... --band``;
* ``report.md``: the numbers, the band, the optimised parameters, the dominant
  modes the shapers are tuned to, and what each method assumes.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from controllers.profiles import (
    ROBUSTNESS_VARIANTS,
    SHAPERS,
    ModelVariant,
    MoveMetrics,
    ProfileOptimisation,
    ProfileSettings,
    command_time,
    dominant_modes,
    evaluate_move,
    optimise_profiles,
    over_variants,
    shaped_scenario,
    time_optimal_scenario,
    write_scenario_profiles,
)
from isolator import SIGNALS, Band, Scenario
from isolator.scenario.arguments import check_public

from .figures import nan_if_none, save_figure
from .reporting import (
    band_lines,
    fmt,
    micro_unit,
    output_folder,
    progress_printer,
    table_header,
    table_row,
    write_json,
    write_report,
)

__all__ = ["ProfileStudy", "run_profile_study"]

@dataclass(frozen=True)
class ProfileStudy:
    """Every method's move, measured.

    Attributes
    ----------
    methods : dict of str to MoveMetrics
        ``paper``, ``zv``, ``zvd``, ``ei``, ``time-optimal``, ``optimised (settling)``,
        ``optimised (cycle)``, nominal model.
    scenarios : dict of str to Scenario
        The scenario each method runs.
    variants : dict of str to list of MoveMetrics
        Per method, the move on each model variant.
    optimisations : dict of str to ProfileOptimisation
        ``settling`` and ``cycle``.
    folder : Path
    band : Band
        5 % of the paper profile's peaks on the nominal model: every method and variant is judged in it.
    files : dict of str to Path
        The scenario file written for each method a scenario file can hold (with ``source``).
    """

    methods: dict[str, MoveMetrics]
    scenarios: dict[str, Scenario]
    variants: dict[str, list[MoveMetrics]]
    optimisations: dict[str, ProfileOptimisation]
    folder: Path
    band: Band
    files: dict[str, Path]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: per method its metrics with the ``band``, and the scenario file written for it."""
        return {name: {**m.to_dict(), "scenario_file": str(self.files[name]) if name in self.files else None,
                       "variants": [v.to_dict() for v in self.variants[name]]}
                for name, m in self.methods.items()}


def run_profile_study(
    folder: str | Path,
    scenario: Scenario,
    variants: tuple[ModelVariant, ...] = ROBUSTNESS_VARIANTS,
    progress: bool = False,
    source: str | Path | None = None,
) -> ProfileStudy:
    """Compare the profile methods on a scenario; write figures and ``report.md`` to ``folder``.

    Parameters
    ----------
    folder : str or Path
        The output folder (created if missing): figures, ``report.md`` and the study's data files.
    scenario : Scenario
        Carriages with trapezoids or S-curves (the "paper" profile).
    variants : tuple of ModelVariant
        Optimised over, and every method checked on.
    progress : bool
        Print a line per step on stderr (off by default; ``isolator study`` turns it on).
    source : str or Path, optional
        The scenario's file (or bundled name): each method that a scenario file can hold is written to
        ``scenarios/<method>.toml``.

    Returns
    -------
    ProfileStudy
        Each method's move, settling and cycle times [s] and their spread over the model variants.
    """
    out = output_folder(folder)
    say = progress_printer(progress)
    command = command_time(scenario)
    scenarios: dict[str, Scenario] = {"paper": scenario}
    paper = evaluate_move(scenario, "paper", command)
    peaks = list(paper.peak.values())
    band = Band.of_baseline("paper", paper.peak)
    for kind in SHAPERS:
        scenarios[kind.upper()] = shaped_scenario(scenario, kind, peaks)
    scenarios["time-optimal"] = time_optimal_scenario(scenario)
    optimisations = {}
    for objective in ("settling", "cycle"):
        say(f"optimising for the {objective} time ...")
        result = optimise_profiles(scenario, ProfileSettings(objective=objective, variants=variants),
                                   progress=progress)
        optimisations[objective] = result
        scenarios[f"optimised ({objective})"] = result.scenario
    say("measuring every method on the model variants ...")
    methods = {name: evaluate_move(sc, name, command, band=band) for name, sc in scenarios.items()}
    spread = {name: over_variants(sc, name, command, variants, band) for name, sc in scenarios.items()}
    files: dict[str, Path] = {}
    if source is not None:
        for name, sc in scenarios.items():
            slug = name.lower().replace(" (", "-").replace(")", "").replace(" ", "-")
            written = write_scenario_profiles(source, sc, out / "scenarios" / f"{slug}.toml",
                                              f"{scenario.name}-{slug}")
            if written is not None:
                files[name] = written
    study = ProfileStudy(methods, scenarios, spread, optimisations, out, band, files)
    write_json(out, study.to_dict())
    _plot_profiles(study)
    _plot_response(study)
    _plot_times(study)
    _plot_robustness(study, variants)
    _write_report(study, scenario, peaks, variants)
    return study


def _colours(names: list[str]) -> dict[str, object]:
    cmap = plt.get_cmap("tab10")
    return {n: ("0.3" if n == "paper" else cmap(i)) for i, n in enumerate(names)}


def _plot_profiles(study: ProfileStudy) -> None:
    names = list(study.scenarios)
    colours = _colours(names)
    carriages = study.scenarios["paper"].carriages
    fig, axes = plt.subplots(2, len(carriages), figsize=(6 * len(carriages), 7), sharex=True, squeeze=False)
    for j, carriage in enumerate(carriages):
        stop = max(sc.carriages[j].profile.stop_time for sc in study.scenarios.values())
        t = np.linspace(max(0.0, stop - 1.6), stop + 0.2, 2000)
        for name, sc in study.scenarios.items():
            _, v, a = sc.carriages[j].profile.evaluate(t)
            axes[0, j].plot(t, v, color=colours[name], label=name)
            axes[1, j].plot(t, a, color=colours[name], label=name)
        axes[0, j].set_title(f"{carriage.name}: the end of the move")
        axes[0, j].set_ylabel("speed [m/s]")
        axes[1, j].set_ylabel("acceleration [m/s²]")
        axes[1, j].set_xlabel("time [s]")
        for ax in axes[:, j]:
            ax.grid(True, alpha=0.3)
    axes[0, -1].legend(fontsize=8, loc="lower left")
    fig.suptitle("Carriage profiles: the braking phase that sets the residual vibration")
    fig.tight_layout()
    save_figure(fig, study.folder / "profiles.png")


def _plot_response(study: ProfileStudy) -> None:
    shown = ["paper", "ZV", "optimised (settling)", "optimised (cycle)"]
    colours = _colours(list(study.scenarios))
    fig, axes = plt.subplots(2, 3, figsize=(15, 7.5), sharex=True)
    for ax, signal in zip(axes.T.ravel(), SIGNALS, strict=True):
        scale, unit = micro_unit(signal)
        for name in shown:
            r = study.methods[name].response
            if r.final is None:  # a move that never stops has no final value to settle about
                continue
            stop = r.stop_time
            keep = r.t >= stop - 1.0
            i = SIGNALS.index(signal)
            ax.plot(r.t[keep] - stop, (r.signals[i, keep] - r.final[i]) * scale, color=colours[name], label=name)
        half = study.band.widths[signal] * scale
        ax.axhline(half, color="0.3", lw=0.8, ls=":")
        ax.axhline(-half, color="0.3", lw=0.8, ls=":")
        ax.axvline(0.0, color="k", lw=0.8)
        ax.set_title(f"{signal} about its final value (dotted: the band)")
        ax.set_ylabel(f"{signal} [{unit}]")
        ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time after the stop [s]")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("Table response around the stop: paper profile, ZV shaping and the optimised moves\n"
                 f"settling band: {study.band.how()}, one for every method")
    fig.tight_layout()
    save_figure(fig, study.folder / "response.png")


def _plot_times(study: ProfileStudy) -> None:
    names = list(study.methods)
    x = np.arange(len(names))
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(14, 5), width_ratios=(3, 2))
    moves = [study.methods[n].move_time for n in names]
    settles = [nan_if_none(study.methods[n].settling_time_max) for n in names]
    ax.bar(x, moves, color="tab:blue", label="move")
    ax.bar(x, settles, bottom=moves, color="tab:red", label="settling")
    for xi, m, s in zip(x, moves, settles, strict=True):
        ax.text(float(xi), m + (0 if np.isnan(s) else s) + 0.05, f"{m + s:.2f} s\n(settle {s:.2f})", ha="center",
                fontsize=8)
    ax.set_xticks(x, names, rotation=20)
    ax.set_ylabel("time from the move's command [s]")
    ax.set_ylim(0, max(m + (0 if np.isnan(s) else s) for m, s in zip(moves, settles, strict=True)) * 1.12)
    ax.set_title(f"Cycle time = move + settling (nominal model; band: {study.band.how()})")
    ax.legend(loc="upper right")
    bx.bar(x, settles, color="tab:red")
    bx.set_xticks(x, names, rotation=20)
    bx.set_ylabel("settling time after the stop [s]")
    bx.set_ylim(0, max((v for v in settles if not np.isnan(v)), default=1.0) * 1.12 or 1.0)
    bx.set_title("Settling alone")
    for axis in (ax, bx):
        axis.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    save_figure(fig, study.folder / "times.png")


def _plot_robustness(study: ProfileStudy, variants: tuple[ModelVariant, ...]) -> None:
    names = list(study.variants)
    fig, ax = plt.subplots(figsize=(12, 5))
    width = 0.8 / len(variants)
    cmap = plt.get_cmap("viridis")
    for k, variant in enumerate(variants):
        values = [nan_if_none(study.variants[n][k].settling_time_max) for n in names]
        ax.bar(np.arange(len(names)) + (k - (len(variants) - 1) / 2) * width, values, width,
               color=cmap(k / max(1, len(variants) - 1)), label=variant.label)
    ax.set_xticks(np.arange(len(names)), names, rotation=20)
    ax.set_ylabel("largest settling time [s]")
    ax.set_title("Settling time on models that are off (isolator stiffness k, damping c, payload mass m); "
                 f"band: {study.band.how()}", fontsize=10)
    ax.legend(fontsize=8, ncol=4)
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    save_figure(fig, study.folder / "robustness.png")


def _write_report(study: ProfileStudy, scenario: Scenario, peaks: list[float],
                  variants: tuple[ModelVariant, ...]) -> None:
    def f(value: float | None) -> str:
        return fmt(value, ".3f")

    lines = [f"# Profile study: {scenario.name}", "",
             "Every method is judged by the exact time-varying simulation. Move time counts from the "
             f"move's command (t = {command_time(scenario):g} s); cycle = move + settling.", "",
             *band_lines(study.band, "One band for every method and model variant: the paper's 5 % criterion "
                         "applied to the paper profile's run, the baseline. Each run's own 5 % would judge a "
                         "method that excites the table less in a narrower band and hide what it gains (or "
                         "penalise it); residual vibration is compared against one tolerance, as a stage "
                         "would be. `results.json` gives each method's settling time with this band; "
                         "`scenarios/<method>.toml` the methods a scenario file can hold.", "SCENARIO.toml"),
             "",
             *table_header(["method", "move [s]", "settling [s]", "cycle [s]",
                            "settling over the model variants [s]"])]
    for name, m in study.methods.items():
        values = [v.settling_time_max for v in study.variants[name] if v.settling_time_max is not None]
        span = f"{min(values):.3f} .. {max(values):.3f}" if values else "n/a"
        lines.append(f"| {name} | {m.move_time:.3f} | {f(m.settling_time_max)} | {f(m.cycle_time)} | {span} |")
    paper = study.methods["paper"]
    best = study.methods["optimised (settling)"]
    lines += ["", "## Targets", ""]
    if paper.settling_time_max and best.settling_time_max is not None:
        ratio = best.settling_time_max / paper.settling_time_max
        lines.append(f"- Settling time of the settling-optimised move: {100 * ratio:.1f} % of the paper profile's "
                     f"(target at most 10 %), with the move {100 * (best.move_time / paper.move_time - 1):.1f} % "
                     "longer (target at most 5 %).")
    zv, cyc = study.methods["ZV"], study.methods["optimised (cycle)"]
    if zv.cycle_time is not None and cyc.cycle_time is not None:
        lines.append(f"- Cycle time of the cycle-optimised move: {cyc.cycle_time:.3f} s against ZV shaping's "
                     f"{zv.cycle_time:.3f} s.")
    lines += ["", "## Peak table motion per method", "",
              *table_header(["method", *(f"{s} [{micro_unit(s)[1]}]" for s in SIGNALS)])]
    for name, m in study.methods.items():
        lines.append(table_row([name, *(f"{m.peak[s] * micro_unit(s)[0]:.3g}" for s in SIGNALS)]))
    lines += ["", "## Optimised parameters", ""]
    for objective, result in study.optimisations.items():
        lines.append(f"**{objective}** (IPOPT {result.status}, {result.iterations} iterations, "
                     f"{result.build_time + result.solve_time:.1f} s, over {len(variants)} models):")
        lines.append("")
        for d in result.designs:
            text = ", ".join(f"{n} = {float(v):.4g}" for n, v in zip(d.names, d.values, strict=True))
            lines.append(f"- {d.name} ({d.shape}): {text}")
        lines.append("")
    lines += ["## Dominant modes (input shapers are tuned to the first of each carriage)", ""]
    for i, carriage in enumerate(scenario.carriages):
        ranked = dominant_modes(scenario, i, peaks)[:3]
        text = ", ".join(f"{m.frequency:.3f} Hz (ζ {m.damping:.3f}, weight {m.weight:.3g})" for m in ranked)
        lines.append(f"- {carriage.name}: {text}")
    lines += ["", "## Assumptions", "",
              "- Limits: each carriage's `limits` (speed, acceleration, jerk), by default its own profile's "
              "speed and acceleration, and a jerk that builds the acceleration in 50 ms for a trapezoid.",
              "- Shapers: ZV, ZVD and EI (5 % tolerance, Singhose's damped fit) convolved with the paper's "
              "trapezoids, each carriage tuned to the mode it excites most at the end position.",
              "- Time-optimal: ruckig, each carriage alone, within its limits, from its own start.",
              "- Optimised: S-curves with separate accelerating and braking jerk, start delay, cruise speed; "
              "objective in each run's own band units over the model variants (the optimiser's measure; the "
              "table above judges the result in the study's one band) "
              f"({', '.join(v.label for v in variants)}).",
              "", "Figures: `profiles.png`, `response.png`, `times.png`, `robustness.png`."]
    write_report(study.folder, lines)


check_public(globals())
