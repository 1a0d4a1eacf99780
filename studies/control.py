"""What active isolation buys: passive, feedforward, feedback and both on an active table.

Run it with ``isolator study control [SCENARIO] --out DIR``. It writes

* ``time.png``: the six table signals in the four runs;
* ``transmissibility.png``: same-axis floor-to-table transmissibility, passive and with each feedback design
  (feedforward does not change it);
* ``settling.png``: 5 % settling time per signal and run (one band: 5 % of the passive run's peaks, kind
  ``baseline``);
* ``forces.png``: the actuators' forces in the three active runs;
* ``results.json``: per run its settling times and the ``band`` they are measured in (six half-widths, m and
  rad), and ``feedforward.csv``, the feedforward forces, so that ``isolator simulate SCENARIO --forces
  feedforward.csv --band ...`` reproduces the feedforward run's numbers;
* ``report.md``: the numbers, the band, the controller and its loop's stability;
* with ``[[sensors]]``, the output-feedback designs the machine can run (:mod:`studies.control_sensors`):
  ``sensors-defaults.png`` (the defaults against the methods' own weights), ``sensors-loops.png``,
  ``sensors-margins.png``, ``sensors-time.png``, ``sensors-budget.png`` (the error budget at the tool:
  :mod:`studies.control_budget`) and their section of the report;
* with ``bending`` (``--bending``; always when the top bends and has sensors), the bending-top case
  (:mod:`studies.control_bending`): ``bending-defaults.png`` (the default designs' settling and margins on the
  rigid and the bending top), ``bending-compliance.png`` (the corner's compliance, open and closed loop) and a
  stiff design the check refuses, with its growing mode, in the report.

With feedback alone the controller regulates to the initial equilibrium (state-feedback lqr and hinf, which
would fight the carriages' quasi-static tilt with saturating forces, to the planned move's quasi-static path:
:attr:`~controllers.feedback.Controller.follows_path`); with both, to the feedforward's quasi-static path, so
the two do not fight over the tilt.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

import matplotlib.pyplot as plt
import numpy as np

from controllers import feedback as fb
from controllers.feedback.output_feedback import checked_sample_rate
from controllers.feedforward import (
    Feedforward,
    feedforward_allocation,
    feedforward_optimal,
    path_deviation,
    run_quasi_static,
    settling_in_band,
)
from isolator import SIGNALS, Band, OptimisationError, ParameterError, Response, Scenario, ScenarioError, Simulator
from isolator.analysis.linear import LinearModel, linearise
from isolator.analysis.transmissibility import transmissibility
from isolator.scenario.arguments import check_public

from . import control_bending as bending_study
from . import control_sensors as sensor_study
from .control_bending_report import FIGURES as BENDING_FIGURES
from .control_bending_report import bending_figures, bending_report
from .control_figures import COLORS, RUNS, forces_figure, time_figure
from .figures import nan_if_none, save_figure
from .reporting import (
    band_lines,
    fmt,
    largest,
    micro_unit,
    output_folder,
    progress_printer,
    table_header,
    table_row,
    write_json,
    write_report,
)
from .throughput import window_cycle

__all__ = ["CONTROLLERS", "ControlStudy", "design", "run_control_study"]

CONTROLLERS = ("skyhook", "lead", "lqr", "hinf")
#: what the feedback-alone run regulates to, by the controller's follows_path
_ALONE = {False: "the initial equilibrium",
          True: "the planned move's quasi-static path (a state-feedback design: about the initial equilibrium its "
          "micrometre weights would fight the carriages' quasi-static tilt)"}


def design(name: str, lin: LinearModel) -> fb.Controller:
    """The study's design of each controller (default parameters, documented in the report).

    Raises
    ------
    ParameterError
        Unknown name, or ``hinf`` without slycot.
    OptimisationError
        ``hinf`` finds no controller.
    """
    if name == "skyhook":
        return fb.skyhook(lin, 5e4)
    if name == "lead":
        return fb.lead(lin, 1e5, 2.0, 20.0)
    if name == "lqr":
        return fb.lqr(lin)
    if name == "hinf":
        return fb.hinf(lin)
    raise ParameterError(f"controller: must be one of {', '.join(CONTROLLERS)}, got '{name}'")


@dataclass(frozen=True)
class ControlStudy:
    """The four runs and what was measured.

    Attributes
    ----------
    runs : dict of str to Response
        ``passive``, ``feedforward``, ``feedback``, ``both``.
    settling : dict of str to dict
        Per run, settling time per signal [s] (None: not within the run) in
        ``band``.
    deviation : dict of str to dict
        Per run, the largest deviation from the quasi-static path per signal [m, rad].
    controller : fb.Controller
    stability : fb.LoopStability
        Of the sampled loop with the carriages at their start.
    folder : Path
    band : Band
        5 % of the passive run's peaks (kind ``baseline``): every run is judged in it.
    max_force : tuple of float
        Each actuator's saturation [N], as the runs' actuator forces are ordered.
    sensors : tuple of SensorDesign
        The output-feedback designs from the scenario's ``[[sensors]]`` (none without sensors).
    sensors_left_out : dict
        The output-feedback methods that could not be designed on the scenario, with the reason.
    bending : BendingCase or None
        The bending-top case (:mod:`studies.control_bending`), when asked for or the scenario's top bends.
    """

    runs: dict[str, Response]
    settling: dict[str, dict[str, float | None]]
    deviation: dict[str, dict[str, float]]
    controller: fb.Controller
    stability: fb.LoopStability
    feedforward: Feedforward
    folder: Path
    band: Band
    max_force: tuple[float, ...] = ()
    sensors: tuple[sensor_study.SensorDesign, ...] = ()
    sensors_left_out: dict[str, str] = field(default_factory=dict)
    bending: bending_study.BendingCase | None = None

    def settling_time_max(self, run: str) -> float | None:
        return largest(self.settling[run].values())

    def saturation(self, run: str) -> str:
        """When the run's actuators sit at their ``max_force``, in words ("" when they never do)."""
        r = self.runs[run]
        if len(self.max_force) != r.actuator_forces.shape[0] or not r.actuator_forces.size:
            return ""
        limit = np.asarray(self.max_force, dtype=float)
        at = np.any(np.abs(r.actuator_forces) >= limit[:, None] * (1 - 1e-6), axis=0)
        if not at.any():
            return ""
        size = f"{limit[0]:g} N" if np.all(limit == limit[0]) else \
            f"their max_force ({limit.min():g}-{limit.max():g} N)"
        last = "the run's end" if at[-1] else f"t = {r.t[at.size - 1 - int(np.argmax(at[::-1]))]:.3g} s"
        return f"its actuators saturate at {size} from t = {r.t[int(np.argmax(at))]:.3g} s to {last}"

    def unsettled_reason(self, run: str) -> str:
        """Why the run shows no settling time ("" when it does): its actuators' saturation, else the first
        signal's reason."""
        if self.settling_time_max(run) is not None:
            return ""
        reasons = [r.reason for r in self.runs[run].with_band(self.band).settling.values() if r.time is None]
        return self.saturation(run) or next(iter(reasons), "")

    def window_cycle(self, run: str) -> tuple[float | None, float | None]:
        """With ``[[windows]]``: the run's largest window settling time [s] and the moves per hour it allows
        (:func:`studies.throughput.window_cycle`); else (None, None)."""
        return window_cycle(self.runs[run])

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for run in RUNS:
            out[run] = {"settling_time": self.settling[run], "settling_time_max": self.settling_time_max(run),
                        "deviation_peak": self.deviation[run],
                        "max_force": float(np.abs(self.runs[run].actuator_forces).max(initial=0.0)),
                        "band": self.band.to_dict()}
            if self.runs[run].windows is not None:
                settle, rate = self.window_cycle(run)
                out[run].update(window_settling_time_max=settle, moves_per_hour=rate)
        if self.sensors or self.sensors_left_out:
            out["sensor_feedback"] = {d.method: d.to_dict() for d in self.sensors}
            out["sensor_feedback_left_out"] = self.sensors_left_out
        if self.bending is not None:
            out["bending_top"] = self.bending.to_dict()
        return out


def run_control_study(out: str | Path, scenario: Scenario, controller: str = "skyhook", feedforward: str = "allocation",
                      progress: bool = False, sample_rate: float = 2000.0, bending: bool = False,
                      quick: bool = False) -> ControlStudy:
    """Run the study and write its figures and report into ``out``.

    Parameters
    ----------
    out : path
        Folder (created).
    scenario : Scenario
        With ``[[actuators]]``.
    controller : {"skyhook", "lead", "lqr", "hinf"}
        The feedback design for the time runs (all are shown in the transmissibility).
    feedforward : {"allocation", "optimal"}
        The feedforward from the planned motion (see :mod:`controllers.feedforward`).
    progress : bool
        Print what it does on stderr (off by default; ``isolator study`` turns it on).
    sample_rate : float
        The sensor-based designs' rate [Hz] (with ``[[sensors]]``: :mod:`studies.control_sensors`).
    bending : bool
        Add the bending-top case (:mod:`studies.control_bending`; always on a scenario with ``[[sensors]]`` whose
        top bends): the
        default sensor-based designs on the rigid and the bending top, the compliance at the corner, a stiff
        design the check refuses.
    quick : bool
        The bending-top case reduced (skyhook only, its own gain).

    Returns
    -------
    ControlStudy
        The runs (passive, feedforward, feedback, both), their settling and the sensor-based designs.
    """
    if not scenario.actuators:
        raise ScenarioError("actuators: the control study needs a scenario with [[actuators]]")
    if feedforward not in ("allocation", "optimal"):
        raise ParameterError(f"feedforward: must be 'allocation' or 'optimal', got '{feedforward}'")
    sample_rate = checked_sample_rate(sample_rate)
    bending = bending or (scenario.table.flexible is not None and bool(scenario.sensors))
    if bending:
        bending_study.bending_pair(scenario)  # a table the case cannot bend is refused before the runs
    folder = output_folder(out)
    say = progress_printer(progress, "  control study: ")
    lin = linearise(scenario)
    ctrl = design(controller, lin)
    sim = Simulator(scenario)
    say("passive run")
    runs = {"passive": sim.run()}
    say(f"feedforward ({feedforward})")
    ff = feedforward_optimal(scenario, progress=progress) if feedforward == "optimal" else \
        feedforward_allocation(scenario)
    runs["feedforward"] = sim.run(forces=ff.forces)
    say(f"feedback ({ctrl.description}) at {ctrl.sample_rate:g} Hz")
    runs["feedback"] = sim.run(feedback=fb.feedback_law(scenario, ctrl))
    say("feedforward and feedback")
    runs["both"] = sim.run(forces=ff.forces, feedback=fb.feedback_law(scenario, ctrl, reference=ff.path))
    band = Band.of_baseline("passive", runs["passive"].peak)
    settling = {name: settling_in_band(r, band) for name, r in runs.items()}
    qs = ff.path(runs["passive"].t).T  # pneumatic tables: each run's own leveling path (as compare_feedforward)
    deviation = {name: path_deviation(r, run_quasi_static(sim, r) if scenario.is_pneumatic else qs)
                 for name, r in runs.items()}
    designs, left_out = sensor_study.run_sensor_designs(scenario, band, settling_in_band, sample_rate, say=say) \
        if scenario.sensors else ([], {})
    sensors = tuple(designs)  # the output-feedback designs: the machine's own sensors, exported controllers
    case = None
    if bending:  # on a rigid scenario its rigid top's designs are the study's own
        known = {d.method: d.controller for d in sensors} if scenario.table.flexible is None else {}
        case = bending_study.run_bending_case(scenario, band, sample_rate, quick, known, say=say)
    study = ControlStudy(runs, settling, deviation, ctrl, fb.check_stability(lin, ctrl), ff, folder, band,
                         tuple(a.max_force for a in scenario.actuators), sensors, left_out, case)
    write_json(folder, study.to_dict())
    ff.forces.to_csv(folder / "feedforward.csv")
    say("figures and report")
    time_figure(runs, folder / "time.png")
    loops = _transmissibility_figure(scenario, lin, folder / "transmissibility.png")
    _settling_figure(study, folder / "settling.png")
    forces_figure(runs, folder / "forces.png")
    if sensors:
        sensor_study.write_figures(sensors, scenario, runs["passive"], band, folder)
    if case is not None:
        bending_figures(case, folder)
    _report(study, scenario, loops)
    return study


# -- figures --------------------------------------------------------------------------
def _transmissibility_figure(scenario: Scenario, lin: LinearModel, path: Path) -> dict[str, Any]:
    f = np.logspace(-1, 2, 600)
    loops: dict[str, Any] = {"passive (and with feedforward)": transmissibility(lin, f)}
    for name in CONTROLLERS:
        try:
            ctrl = design(name, lin)
        except (ParameterError, OptimisationError):  # hinf without slycot or no design; state feedback on air
            if name != "hinf" and not (name == "lqr" and lin.air is not None):
                raise
            continue
        # the closed loop answers what transmissibility asks of a LinearModel (frequency_response, scenario)
        loop = cast(LinearModel, fb.closed_loop(lin, ctrl, check=False))
        loops[ctrl.name] = transmissibility(loop, f)
    fig, axes = plt.subplots(2, 3, figsize=(13, 7), sharex=True, layout="constrained")
    for i, axis in enumerate(SIGNALS):
        ax = axes[i // 3, i % 3]
        for k, (name, resp) in enumerate(loops.items()):
            ax.loglog(f, resp.magnitude(axis), label=name, color="0.2" if k == 0 else None,
                      lw=1.8 if k == 0 else 1.1)
        ax.axhline(1.0, color="0.6", lw=0.8, ls="--")
        ax.set_title(f"{axis} from floor {axis}")
        ax.set_ylabel("|T| [m/m]" if i < 3 else "|T| [rad/rad]")
        ax.grid(True, which="both", alpha=0.3)
        if i >= 3:
            ax.set_xlabel("frequency [Hz]")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"Transmissibility with and without feedback ({scenario.name}, carriages at their start)")
    save_figure(fig, path)
    return loops


def _settling_figure(study: ControlStudy, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(11, 4.8), layout="constrained")
    labels = [*SIGNALS, "largest"]
    width = 0.2
    x = np.arange(len(labels))
    top = 0.0
    for j, run in enumerate(RUNS):
        values = [study.settling[run][k] for k in SIGNALS] + [study.settling_time_max(run)]
        heights = [nan_if_none(v) for v in values]
        top = max(top, np.nanmax(heights, initial=0.0))
        bars = ax.bar(x + (j - 1.5) * width, heights, width, label=run, color=COLORS[run])
        for bar, v in zip(bars, values, strict=True):
            text = "n/a" if v is None else f"{v:.2f}"
            ax.text(bar.get_x() + bar.get_width() / 2, (0 if v is None else v), text, ha="center", va="bottom",
                    fontsize=7, rotation=90)
    ax.set_xticks(x, labels)
    ax.set_ylim(0, 1.25 * top if top > 0 else 1.0)
    ax.set_ylabel("5 % settling time after the stop [s]")
    ax.set_title(f"Settling time per signal (band: {study.band.how()}; n/a: not settled within the run)")
    ax.legend()
    ax.grid(True, axis="y", alpha=0.3)
    save_figure(fig, path)


# -- report ---------------------------------------------------------------------------
def _report(study: ControlStudy, scenario: Scenario, loops: dict[str, Any]) -> None:
    ctrl = study.controller
    lines = [
        f"# Active isolation study: {scenario.name}",
        "",
        f"Feedforward: {study.feedforward.method}. Feedback: {ctrl.description}, run at {ctrl.sample_rate:g} Hz "
        f"(Tustin), sampled-loop spectral radius {study.stability.spectral_radius:.4f} "
        f"({'stable' if study.stability.stable else 'UNSTABLE'}), slowest continuous decay "
        f"{study.stability.margin:.3g} 1/s.",
        "With feedback alone the controller regulates to "
        f"{_ALONE[ctrl.follows_path]}; with both, to the feedforward's quasi-static path.",
        "",
        *band_lines(study.band, "One band for all four runs, about each run's final value: the question is how "
                    "fast each controller brings the table back to within what the passive table calls settled, "
                    "so the runs are compared on the passive run's band, not each on its own peak (a controller "
                    "that halves the peak would otherwise be judged in a band half as wide). The settling times "
                    "in `results.json` carry this band; the passive run is `isolator simulate` of the scenario "
                    "with it, the feedforward run adds `--forces feedforward.csv`, the feedback runs are "
                    "`Simulator.run(feedback=..., band=...)`.", scenario.name),
        "",
        "## Settling time after the stop and peak deviation from the quasi-static path",
        "",
        *table_header(["run", "settling, largest", *(f"settling {k}" for k in SIGNALS), "largest force"]),
    ]
    for run in RUNS:
        force = float(np.abs(study.runs[run].actuator_forces).max(initial=0.0))
        lines.append(table_row([run, fmt(study.settling_time_max(run), suffix=" s"),
                                *(fmt(study.settling[run][k], suffix=" s") for k in SIGNALS), f"{force:.0f} N"]))
    lines += ["", *(f"- {run}: no settling time: {study.unsettled_reason(run)}." for run in RUNS
                    if study.settling_time_max(run) is None)]
    if study.runs["passive"].windows is not None:
        lines += ["", "## At the windows: settling and moves per hour", "",
                  "The largest window settling time (absolute windows at the `[[points]]`, about each run's "
                  "settled position) and the moves per hour a machine repeating the move would make "
                  "(3600 / (move time + window settling)).", "",
                  *table_header(["run", "window settling", "moves per hour"])]
        for run in RUNS:
            settle, rate = study.window_cycle(run)
            lines.append(table_row([run, fmt(settle, suffix=" s"), fmt(rate, ".0f")]))
    lines += ["", *table_header(["run", *(f"dev. {k}" for k in SIGNALS)])]
    for run in RUNS:
        dev = study.deviation[run]
        lines.append(table_row([run, *(f"{dev[k] * micro_unit(k)[0]:.3g} {micro_unit(k)[1]}" for k in SIGNALS)]))
    lines += ["", "## Transmissibility peaks (same axis, carriages at their start)", "",
              *table_header(["design", *SIGNALS])]
    for name, resp in loops.items():
        lines.append(table_row([name, *(f"{resp.peak(a)[0]:.3g} at {resp.peak(a)[1]:.3g} Hz" for a in SIGNALS)]))
    extra = "".join(f", `{name}`" for name in (*sensor_study.FIGURES, *BENDING_FIGURES)
                    if (study.folder / name).exists())
    lines += ["", *sensor_study.sensor_report(study.sensors, study.sensors_left_out),
              *bending_report(study.bending),
              f"Figures: `time.png`, `transmissibility.png`, `settling.png`, `forces.png`{extra}."]
    write_report(study.folder, lines)


check_public(globals())
