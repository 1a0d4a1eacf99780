"""How the stage should move through a step-and-settle sequence: total time and throughput per method.

``isolator study profiles SCENARIO --out DIR`` on a scenario with a ``[sequence]`` runs this study. Every
method moves the same steps and is judged by the same window rule on the exact time-varying model
(:func:`isolator.simulation.sequence.run_sequence`):

* ``S-curve at the limits``: each step a seven-segment S-curve at the carriages' limits (per-step limits,
  delays and shapers of the file left out: an optimised sequence is compared from where it started);
* ``time-optimal (ruckig)``: ruckig's jerk-limited time-optimal move per step (for rest-to-rest moves it is
  the S-curve at the limits: the two agree, a check of both);
* ``ZV`` and ``ZVD``: the S-curves convolved with input shapers tuned per step to the mode the carriage
  excites most where the step ends;
* ``optimised``: each step's S-curve limits, start delays and input shaper designed for the least total
  time (:func:`controllers.profiles.sequence_design.optimise_sequence`).

It writes ``throughput.png`` (total time split into move, settle and measure, and the throughput, per
method), ``steps.png`` (each step's move + settle per method), ``sequence.png`` (the optimised sequence:
the probe's deviation, the window, the phases), ``results.json``, ``report.md`` and, given the scenario's
file, ``scenarios/optimised.toml`` (the optimised sequence, for ``isolator sequence``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import MaxNLocator

from controllers.profiles.sequence_baselines import shaped_moves, time_optimal_moves
from controllers.profiles.sequence_design import SequenceOptimisation, optimise_sequence, write_sequence_scenario
from isolator import Scenario, ScenarioError
from isolator.scenario.arguments import check_public
from isolator.scenario.sequence import Move, Step
from isolator.simulation.sequence import SequenceResult, run_sequence

from .figures import save_figure
from .reporting import fmt, output_folder, progress_printer, table_header, table_row, write_json, write_report

__all__ = ["SequenceProfileStudy", "run_sequence_profile_study"]

_BASELINE = "S-curve at the limits"
_PHASES = (("move", "#6baed6"), ("settle", "#fd8d3c"), ("measure", "#74c476"))


@dataclass(frozen=True)
class SequenceProfileStudy:
    """Every method's run of the sequence.

    Attributes
    ----------
    scenario : Scenario
    runs : dict of str to SequenceResult
        By method, the S-curve at the limits first.
    optimisation : SequenceOptimisation
    folder : Path
    files : dict of str to Path
        The scenario files written (``optimised``).
    """

    scenario: Scenario
    runs: dict[str, SequenceResult]
    optimisation: SequenceOptimisation
    folder: Path
    files: dict[str, Path]

    def gain(self, method: str) -> float | None:
        """Throughput of ``method`` over the S-curve at the limits', minus 1 (None: either did not settle)."""
        base, run = self.runs[_BASELINE].throughput, self.runs[method].throughput
        return None if base is None or run is None else run / base - 1.0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: per method the total time, throughput, gain and the sums of move, settle, measure."""
        out: dict[str, Any] = {}
        for name, r in self.runs.items():
            d = r.to_dict()
            out[name] = {"total_time": r.total_time, "throughput_per_hour": r.throughput, "gain": self.gain(name),
                         "move_time": d["move_time"], "settle_time": d["settle_time"],
                         "measure_time": r.measure * len(r.steps), "unsettled": r.unsettled}
        out["optimised"]["designs"] = self.optimisation.to_dict()["moves"]
        if "optimised" in self.files:
            out["optimised"]["scenario_file"] = str(self.files["optimised"])
        return out


def run_sequence_profile_study(
    folder: str | Path, scenario: Scenario, progress: bool = False, source: str | Path | None = None,
    samples: int = 32,
) -> SequenceProfileStudy:
    """Compare the ways of moving through the scenario's sequence; write figures and ``report.md``.

    Parameters
    ----------
    folder : str or Path
        The output folder (created if missing): figures, ``report.md`` and the study's data files.
    scenario : Scenario
        With a ``[sequence]`` and ``[[windows]]``.
    progress : bool
        A line per method on stderr (off by default; ``isolator study`` turns it on).
    source : str or Path, optional
        The scenario's file (or bundled name): the optimised sequence is written to
        ``scenarios/optimised.toml``.
    samples : int
        Of the optimisation (:func:`optimise_sequence`).

    Returns
    -------
    SequenceProfileStudy
        Each way of moving's total time [s] and throughput [steps per hour].

    Raises
    ------
    ScenarioError
        No ``[sequence]``.
    """
    if scenario.sequence is None:
        raise ScenarioError("sequence: the sequence study needs a scenario with a [sequence]")
    out = output_folder(folder)
    say = progress_printer(progress)
    scenario = _at_the_limits(scenario)
    runs: dict[str, SequenceResult] = {}
    say("sequence: the S-curves at the limits, ruckig's time-optimal moves, ZV and ZVD ...")
    runs[_BASELINE] = run_sequence(scenario)
    runs["time-optimal (ruckig)"] = run_sequence(scenario, move=time_optimal_moves())
    for kind in ("zv", "zvd"):
        runs[kind.upper()] = run_sequence(scenario, move=shaped_moves(scenario, kind))
    say("sequence: optimising every step ...")
    optimisation = optimise_sequence(scenario, samples=samples, progress=progress)
    runs["optimised"] = optimisation.after
    files = {}
    if source is not None:
        target = out / "scenarios" / "optimised.toml"
        files["optimised"] = write_sequence_scenario(source, optimisation.scenario, target)
    study = SequenceProfileStudy(scenario, runs, optimisation, out, files)
    write_json(out, study.to_dict())
    _plot_throughput(study)
    _plot_steps(study)
    fig = optimisation.after.plot(title=f"{scenario.name}: the optimised sequence")
    save_figure(fig, out / "sequence.png")
    _write_report(study)
    return study


def _at_the_limits(scenario: Scenario) -> Scenario:
    """The scenario with every step a plain target (the S-curve at the carriages' limits): a sequence
    written with per-step limits, delays or shapers (an optimised one) is compared from where it started."""
    seq = scenario.sequence
    assert seq is not None
    steps = tuple(Step(tuple((name, Move(move.target)) for name, move in step.moves)) for step in seq.steps)
    return replace(scenario, sequence=replace(seq, steps=steps))


def _plot_throughput(study: SequenceProfileStudy) -> None:
    names = list(study.runs)
    data = study.to_dict()
    x = np.arange(len(names))
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(14, 5), width_ratios=(3, 2), constrained_layout=True)
    bottom = np.zeros(len(names))
    for phase, colour in _PHASES:
        values = np.array([data[n][f"{phase}_time"] for n in names], dtype=float)
        ax.bar(x, values, bottom=bottom, color=colour, label=phase)
        bottom += values
    for xi, n in zip(x, names, strict=True):
        total = study.runs[n].total_time
        ax.text(float(xi), float(bottom[xi]) * 1.01, "did not settle" if total is None else f"{total:.1f} s",
                ha="center", va="bottom", fontsize=8)
    ax.set_xticks(x, names, rotation=15)
    ax.set_ylabel("time [s]")
    ax.set_ylim(0, float(bottom.max()) * 1.12)
    ax.set_title(f"Total time of the {len(study.scenario.sequence.steps) if study.scenario.sequence else 0} steps: "
                 "move + settle (window) + measure", fontsize=10)
    ax.legend(loc="upper right")
    rates = [study.runs[n].throughput or 0.0 for n in names]
    bx.bar(x, rates, color=["0.45" if n == _BASELINE else "tab:blue" for n in names])
    for xi, n, r in zip(x, names, rates, strict=True):
        g = study.gain(n)
        bx.text(float(xi), r * 1.01, f"{r:.0f}" + ("" if g is None or n == _BASELINE else f"\n({round(g * 100):+d} %)"),
                ha="center", va="bottom", fontsize=8)
    bx.set_xticks(x, names, rotation=15)
    bx.set_ylabel("throughput [steps per hour]")
    bx.set_ylim(0, max(rates) * 1.2 or 1.0)
    bx.set_title("Throughput (gain over the S-curve at the limits)", fontsize=10)
    for axis in (ax, bx):
        axis.grid(True, axis="y", alpha=0.3)
    fig.suptitle(f"{study.scenario.name}: step-and-settle throughput per way of moving")
    save_figure(fig, study.folder / "throughput.png")


def _plot_steps(study: SequenceProfileStudy) -> None:
    fig, ax = plt.subplots(figsize=(12, 4.5), constrained_layout=True)
    for name, r in study.runs.items():
        steps = [s for s in r.steps if s.settled is not None]
        ax.plot([s.index for s in steps], [s.settled - s.start for s in steps if s.settled is not None],
                "o--" if name.startswith("time-optimal") else "o-",  # on top of the S-curve: dashed to show both
                ms=3, lw=1.2, label=name, color="0.3" if name == _BASELINE else None)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("step")
    ax.set_ylabel("move + settle [s]")
    ax.set_ylim(bottom=0)
    ax.set_title("Each step's move and settle (until every window holds), per way of moving", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, ncol=3)
    save_figure(fig, study.folder / "steps.png")


def _write_report(study: SequenceProfileStudy) -> None:
    sc = study.scenario
    seq = sc.sequence
    assert seq is not None
    windows = "; ".join(f"{w.point} ±{w.translation * 1e9:.4g} nm on {','.join(w.axes)}" for w in sc.windows)
    lines = [f"# Step-and-settle throughput: {sc.name}", "",
             f"{len(seq.steps)} steps, measuring {seq.measure:g} s at each; windows: {windows}. Every method is "
             "judged by the window rule on the exact time-varying model.", "",
             *table_header(["method", "total [s]", "throughput [steps/h]", "gain", "move [s]", "settle [s]"])]
    data = study.to_dict()
    for name in study.runs:
        d = data[name]
        gain = "" if d["gain"] is None or name == _BASELINE else f"{d['gain'] * 100:+.1f} %"
        lines.append(table_row([name, fmt(d["total_time"], ".2f"), fmt(d["throughput_per_hour"], ".0f"), gain,
                                fmt(d["move_time"], ".2f"), fmt(d["settle_time"], ".2f")]))
    zvd, opt = study.runs["ZVD"].throughput, study.runs["optimised"].throughput
    if zvd and opt:
        lines += ["", f"The optimised sequence against ZVD: {(opt / zvd - 1) * 100:+.1f} % throughput."]
    lines += ["", "## The optimised moves", "", study.optimisation.summary().replace("\n", "  \n"), "",
              "## What each method assumes", "",
              "- S-curve at the limits: the fastest jerk-limited move, blind to the table.",
              "- Time-optimal (ruckig): the same limits solved by ruckig; equal to the S-curve for rest-to-rest "
              "moves.",
              "- ZV / ZVD: the S-curve convolved with a shaper tuned to the mode each carriage excites most where "
              "the step ends (linearised table); longer moves, far less residual vibration.",
              "- Optimised: per distinct move, the S-curve's limits (within the carriages'), start delays and an "
              "input shaper's frequency and damping searched on the exact model by the window rule itself.",
              "", "Figures: `throughput.png`, `steps.png`, `sequence.png`."]
    if "optimised" in study.files:
        lines.append(f"Optimised sequence: `{study.files['optimised']}` (`isolator sequence` runs it).")
    write_report(study.folder, lines)


check_public(globals())
