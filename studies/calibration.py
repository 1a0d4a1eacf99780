"""What calibration buys: a profile optimised on the datasheet model and one optimised on the calibrated model,
both run on the true table.

Run it with ``isolator study calibration [CALIBRATION.toml] --out DIR [--true TRUE.toml]`` (default: the
bundled example, whose SYNTHETIC records the MuJoCo check made of ``true.toml``, isolators 15-30 % off the
datasheet). The calibration is fitted; the carriages' S-curves are optimised (settling-time objective, the
nominal model only, so that each design trusts its model) on the datasheet scenario and on the fitted one;
then the paper's profile and both optimised profiles are simulated on the true table and judged in one band
(1 % of the paper profile's peaks on the true table, a precision machine's tolerance; ``fraction``):

* ``calibration.png``: the fit (H1 and traces against the nominal and fitted model, the parameters);
* ``settling.png``: each design's settling time as its own model predicts it and on the true table;
* ``residual.png``: the table's largest signal after the stop on the true table, per design;
* ``report.md``: the parameters with their intervals, the settling times, what the datasheet design leaves.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from controllers.profiles import (
    ModelVariant,
    MoveMetrics,
    ProfileSettings,
    command_time,
    evaluate_move,
    optimise_profiles,
)
from isolator import SIGNALS, Band, Scenario, load_scenario
from isolator.calibration import CalibrationResult, bundled_calibrations, calibrate
from isolator.scenario.arguments import check_public

from .figures import nan_if_none, save_figure
from .reporting import fmt, output_folder, progress_printer, table_header, table_row, write_report

__all__ = ["CalibrationStudy", "example_calibration", "run_calibration_study"]

def example_calibration() -> Path:
    """The bundled calibration example's file (SYNTHETIC records of ``true.toml`` beside it)."""
    return bundled_calibrations()["table-3-2"]


@dataclass(frozen=True)
class CalibrationStudy:
    """The calibration and the designs it compares.

    Attributes
    ----------
    result : CalibrationResult
    predicted : dict of str to MoveMetrics
        ``datasheet`` and ``calibrated``: each optimised design on the model it was optimised on.
    actual : dict of str to MoveMetrics
        ``paper``, ``datasheet``, ``calibrated``: each on the true table, in one band.
    folder : Path
    """

    result: CalibrationResult
    predicted: dict[str, MoveMetrics]
    actual: dict[str, MoveMetrics]
    folder: Path


def run_calibration_study(out: str | Path, calibration: str | Path | None = None, truth: str | Path | None = None,
                          fraction: float = 0.01, progress: bool = False) -> CalibrationStudy:
    """Run the study (see the module's description); figures and ``report.md`` in ``out``.

    Parameters
    ----------
    out : str or Path
        Output folder (made if missing).
    calibration : str or Path, optional
        A calibration file (default: the bundled example).
    truth : str or Path, optional
        The true table's scenario (default: ``true.toml`` beside the calibration file).
    fraction : float
        The settling band: this fraction of the paper profile's peaks (on the model a design is predicted on,
        on the true table for the runs there); 1 %: a precision machine's tolerance, where the residual
        vibration a wrong model leaves shows (in 5 % both optimised designs are inside at once).
    progress : bool
        Print what it does on stderr (off by default; ``isolator study`` turns it on).

    Returns
    -------
    CalibrationStudy
        The calibration, the designs optimised on the datasheet and the calibrated model, and each design's
        predicted and true settling times [s].
    """
    folder = output_folder(out)
    say = progress_printer(progress, "calibration study: ")
    path = Path(calibration) if calibration is not None else example_calibration()
    if not path.exists() and str(path) in bundled_calibrations():
        path = bundled_calibrations()[str(path)]
    true = load_scenario(Path(truth) if truth is not None else path.parent / "true.toml")
    say(f"fitting {path}")
    result = calibrate(path)
    datasheet = load_scenario(result.calibration.scenario_file)
    settings = ProfileSettings(objective="settling", variants=(ModelVariant(),))
    designs: dict[str, Scenario] = {}
    predicted: dict[str, MoveMetrics] = {}
    command = command_time(datasheet)
    for label, model in (("datasheet", datasheet), ("calibrated", result.scenario)):
        say(f"optimising the profiles on the {label} model")
        optimised = optimise_profiles(model, settings)
        designs[label] = optimised.scenario
        own = Band.of_baseline("paper", evaluate_move(model, "paper", command).peak, fraction)
        predicted[label] = evaluate_move(optimised.scenario, label, command, band=own)
    on_true = {"paper": true, **{k: replace(true, carriages=s.carriages) for k, s in designs.items()}}
    paper = evaluate_move(on_true["paper"], "paper", command)
    band = Band.of_baseline("paper", paper.peak, fraction)
    say("running every design on the true table")
    actual = {k: evaluate_move(s, k, command, band=band) for k, s in on_true.items()}
    study = CalibrationStudy(result, predicted, actual, folder)
    result.plot(folder / "calibration.png")
    plt.close("all")
    _settling_figure(study, folder / "settling.png")
    _residual_figure(study, folder / "residual.png")
    _report(study, path, folder, fraction, Path(truth) if truth is not None else path.parent / "true.toml")
    return study


def _settling_figure(study: CalibrationStudy, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(7.5, 4.2), layout="constrained")
    labels = ["paper", "datasheet", "calibrated"]
    x = np.arange(len(labels))
    ax.bar(x - 0.18, [nan_if_none(study.predicted[k].settling_time_max) if k in study.predicted else np.nan
                      for k in labels], 0.36, color="C0", label="predicted by the model it was designed on")
    ax.bar(x + 0.18, [nan_if_none(study.actual[k].settling_time_max) for k in labels], 0.36, color="C3",
           label="on the true table")
    ax.set_xticks(x, ["paper profile", "optimised on\ndatasheet model", "optimised on\ncalibrated model"])
    ax.set_ylabel("settling time after the stop [s]")
    ax.set_ylim(bottom=0)
    share = study.actual["paper"].band.fraction
    ax.set_title("What calibration buys: settling time of each design\n"
                 f"(band: {share:.0%} of the paper profile's peaks)")
    ax.legend(fontsize=8)
    save_figure(fig, path)


def _residual_figure(study: CalibrationStudy, path: Path) -> None:
    """The signal the datasheet design settles last in, after the stop, zoomed on the band."""
    paper = study.actual["paper"].response
    late = study.actual["datasheet"].response.settling_time
    signal = max(SIGNALS, key=lambda s: -1.0 if late[s] is None else float(late[s]))  # type: ignore[arg-type]
    k = SIGNALS.index(signal)
    scale, unit = (1e6, "µm") if k < 3 else (1e6, "µrad")
    width = paper.band.widths[signal] * scale
    fig, ax = plt.subplots(figsize=(8.5, 4.2), layout="constrained")
    largest = 0.0
    for label, color in (("paper", "0.5"), ("datasheet", "C0"), ("calibrated", "C3")):
        r = study.actual[label].response
        after = r.t >= r.stop_time
        final = 0.0 if r.final is None else float(r.final[k])
        residual = (r.signals[k, after] - final) * scale
        if label != "paper":
            largest = max(largest, float(np.max(np.abs(residual))))
        ax.plot(r.t[after] - r.stop_time, residual, color=color, lw=1.0,
                label=f"{label}: settles in {fmt(study.actual[label].settling_time_max, '.3g', ' s')}")
    ax.axhspan(-width, width, color="0.9", label="band")
    limit = max(6 * width, 1.3 * largest)
    ax.set_ylim(-limit, limit)
    ax.set_xlabel("time after the stop [s]")
    ax.set_ylabel(f"{signal} - final [{unit}]")
    ax.set_title(f"On the true table: the table's {signal} after the stop, per design (the paper's clipped)")
    ax.legend(fontsize=8)
    save_figure(fig, path)


def _report(study: CalibrationStudy, path: Path, folder: Path, fraction: float, truth: Path) -> None:
    r = study.result
    lines = ["# What calibration buys", "",
             f"Calibration `{path}`; the true table `{truth}`"
             " (for the bundled example: SYNTHETIC records of it made by the MuJoCo check, 1 % noise).", "",
             "## The fit", "", "| parameter | datasheet | fitted | 95 % interval |", "|---|---:|---:|---|"]
    for n, e in r.parameters.items():
        lines.append(f"| `{n}` | {e.initial:.5g} | {e.value:.5g} | [{e.ci95[0]:.5g}, {e.ci95[1]:.5g}] |")
    lines += ["", "![fit](calibration.png)", "", "## The designs on the true table", "",
              "The carriages' S-curves optimised for settling time on each model (nominal model only), then run on "
              f"the true table; every run judged in {fraction:.0%} of the paper profile's peaks (predicted: on the "
              "model the design was made on; actual: on the true table).", "",
              *table_header(["design", "move [s]", "predicted settling [s]", "settling on the true table [s]",
                             "cycle on the true table [s]"])]
    for k in ("paper", "datasheet", "calibrated"):
        a = study.actual[k]
        p = study.predicted.get(k)
        lines.append(table_row([k, fmt(a.move_time), "-" if p is None else fmt(p.settling_time_max),
                                fmt(a.settling_time_max), fmt(a.cycle_time)]))
    lines += ["", "![settling](settling.png)", "", "![residual](residual.png)", ""]
    write_report(folder, lines)


check_public(globals())
