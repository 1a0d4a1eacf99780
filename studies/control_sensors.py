"""The control study's sensor-based designs: what controllers the machine can run buy on the table.

For each output-feedback design from the scenario's ``[[sensors]]`` (skyhook, LQG, H-infinity; discrete at
the study's sample rate, as ``isolator controller`` exports them) the study reports

* the carriage move's settling, simulated with the controller in the loop exactly as the exported C runs
  it (noise-free sensors), in the study's band; the peak and RMS actuator force of that run;
* the closed-loop floor-to-sensor transmissibility and the sensitivity and complementary sensitivity at
  the sensors (:mod:`studies.sensor_loops`), carriages at the middle of their travel;
* the margins across the travel (:func:`controllers.feedback.check_robustness`);
* the table's RMS motion and the actuators' RMS command caused by the sensors' noise alone;
* the error budget at the tool, passive and closed loop, with the part the sensors' noise adds
  (:mod:`studies.control_budget`; with a random source on the passive table).

Figures (:data:`FIGURES`, :func:`write_figures`): ``sensors-defaults.png`` (the default designs against the
methods' own weights and the passive table: settling and peak command), ``sensors-loops.png``,
``sensors-margins.png``, ``sensors-time.png`` and ``sensors-budget.png``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from controllers import feedback as fb
from controllers.feedback.output_feedback import travel
from isolator import SIGNALS, Band, OptimisationError, ParameterError, Response, Scenario, ScenarioError, Simulator
from isolator.analysis.linear import linearise
from isolator.scenario.arguments import check_public
from isolator.simulation.discrete_controller import DiscreteController

from .control_budget import DesignBudget, budget_figure, budget_section, design_budget
from .figures import save_figure
from .reporting import fmt, micro_unit, table_header, table_row
from .sensor_loops import LoopResponse, NoiseMotion, loop_response, noise_motion

__all__ = ["FIGURES", "SENSOR_METHODS", "SensorDesign", "defaults_figure", "run_sensor_designs", "sensor_report",
           "write_figures"]

#: the output-feedback designs the study compares
SENSOR_METHODS = ("skyhook", "lqg", "hinf")
#: the figures of the section (``sensors-budget.png`` only when the designs have budgets)
FIGURES = ("sensors-defaults.png", "sensors-loops.png", "sensors-margins.png", "sensors-time.png",
           "sensors-budget.png")


@dataclass(frozen=True)
class SensorDesign:
    """One output-feedback design in the study.

    Attributes
    ----------
    method : str
    controller : DiscreteController
    response : Response
        The carriage move with the controller in the loop (noise-free sensors).
    settling : dict
        Settling time per signal in the study's band [s] (None: not settled).
    loops : LoopResponse
        At the middle of the travel.
    noise : NoiseMotion
    robustness : dict
        The robustness report over the travel's extremes and middle
        (:meth:`controllers.feedback.RobustnessReport.to_dict`).
    travel : tuple of RobustnessCase
        The loop at evenly spaced positions of the scheduling carriage (the others mid-travel), nominal
        isolators: margins along the travel.
    peak_force, rms_force : float
        Largest and RMS applied actuator force over the run [N] (over all actuators).
    unsearched : float or None
        The slowest signal's settling time [s] of the method's own default design (``search=False``), when the
        design's weights came from the search (:mod:`controllers.feedback.output_tuning`); None otherwise or
        when it did not settle.
    force_share : float
        The largest of the actuators' peak commands over their ``max_force``.
    unsearched_share : float
        The same for the method's own default design (nan without a search).
    budget : DesignBudget or None
        The error budget at the tool, passive and with this controller (:func:`studies.control_budget.design_budget`).
    """

    method: str
    controller: DiscreteController
    response: Response
    settling: dict[str, float | None]
    loops: LoopResponse
    noise: NoiseMotion
    robustness: dict[str, Any]
    travel: tuple[fb.RobustnessCase, ...]
    peak_force: float
    rms_force: float
    unsearched: float | None = None
    force_share: float = math.nan
    budget: DesignBudget | None = None
    unsearched_share: float = math.nan

    @property
    def settling_time_max(self) -> float | None:
        """The slowest signal's settling time [s], None when one did not settle."""
        values = list(self.settling.values())
        return None if any(v is None for v in values) else max(v for v in values if v is not None)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {"method": self.method, "sample_rate": self.controller.sample_rate, "states": self.controller.states,
                "settling": self.settling, "settling_time_max": self.settling_time_max,
                "peak_force": self.peak_force, "rms_force": self.rms_force, "force_share": self.force_share,
                "unsearched_settling_time_max": self.unsearched,
                "unsearched_force_share": None if math.isnan(self.unsearched_share) else self.unsearched_share,
                "noise_table_rms": self.noise.table_rms, "noise_force_rms_max": float(np.max(self.noise.force_rms)),
                "sensitivity_peak": float(np.max(self.loops.sensitivity)),
                "complementary_peak": float(np.max(self.loops.complementary)),
                "robustness": self.robustness, "settings": self.controller.settings,
                "budget": None if self.budget is None else self.budget.to_dict()}


def run_sensor_designs(scenario: Scenario, band: Band, settle: Callable[[Response, Band], dict[str, float | None]],
                       sample_rate: float = 2000.0, methods: Sequence[str] = SENSOR_METHODS,
                       say: Callable[[str], None] | None = None) -> tuple[list[SensorDesign], dict[str, str]]:
    """Design, check and simulate each output-feedback method on ``scenario``.

    Parameters
    ----------
    band : Band
        The study's settling band.
    settle : callable
        ``(response, band) -> settling time per signal`` (the study's own rule).
    sample_rate : float
        The controllers' rate [Hz].
    methods : sequence of str
        Of :data:`SENSOR_METHODS`; ``hinf`` is left out when slycot is missing or it has no solution.
    say : callable, optional
        Progress lines.

    Returns
    -------
    designs : list of SensorDesign
    left_out : dict
        Each method that could not be designed on this scenario, with the reason (one line).
    """
    say = say or (lambda text: None)
    skipped: dict[str, str] = {}
    sim = Simulator(scenario)
    middle, _ = fb.design_positions(scenario)
    plant = fb.sensor_plant(linearise(scenario, positions=middle[0]))
    f = np.logspace(-1, math.log10(0.45 * sample_rate), 400)
    limits = np.array([a.max_force for a in scenario.actuators])
    out = []
    for method in methods:
        say(f"sensor feedback: {method} at {sample_rate:g} Hz")
        try:
            ctrl = fb.design_controller(scenario, method, sample_rate)
        except (ParameterError, ScenarioError, OptimisationError) as exc:  # e.g. no collocated geophones
            say(f"  {method} left out: {exc}")
            skipped[method] = str(exc)
            continue
        robust = fb.check_robustness(scenario, ctrl)
        along = fb.check_robustness(scenario, ctrl, positions=[tuple(q) for q in _along_travel(scenario)])
        response = sim.run(controller=ctrl)
        forces = response.actuator_forces
        unsearched, unsearched_share = None, math.nan
        if "search" in ctrl.settings:  # the method's own default weights, for the comparison
            own_run = sim.run(controller=fb.design_controller(scenario, method, sample_rate, search=False))
            own = settle(own_run, band)
            unsearched = None if any(v is None for v in own.values()) else max(v for v in own.values() if v is not None)
            unsearched_share = _share(own_run, limits)
        out.append(SensorDesign(method, ctrl, response, settle(response, band), loop_response(plant, ctrl, f),
                                noise_motion(plant, ctrl), robust.to_dict(), along.cases,
                                float(np.max(np.abs(forces))), float(np.sqrt(np.mean(forces**2))), unsearched,
                                _share(response, limits), design_budget(scenario, ctrl), unsearched_share))
    return out, skipped


def _share(response: Response, limits: np.ndarray) -> float:
    """The largest of the actuators' peak commands in ``response`` over their ``max_force``."""
    return float(np.max(np.max(np.abs(response.actuator_forces), axis=1) / limits))


def _along_travel(scenario: Scenario, points: int = 9) -> np.ndarray:
    """Positions (points, carriages) [m] along the travel of the carriage that schedules by default (the
    carriages at mid-travel, one point, when none travels)."""
    ranges = travel(scenario)
    if not ranges.size or not np.any(ranges[:, 1] > ranges[:, 0]):
        return fb.design_positions(scenario)[0]
    positions, index = fb.design_positions(scenario, 2)
    lo, hi = positions[0, index], positions[-1, index]
    out = np.repeat(positions[:1], points, axis=0)
    out[:, index] = np.linspace(lo, hi, points)
    return out


def write_figures(designs: Sequence[SensorDesign], scenario: Scenario, passive: Response, band: Band,
                  folder: Path) -> None:
    """The section's figures in ``folder``: ``sensors-loops.png``, ``sensors-margins.png``, ``sensors-time.png``
    and (with budgets) ``sensors-budget.png``."""
    defaults_figure(designs, passive, band, folder / "sensors-defaults.png")
    loops_figure(designs, scenario, folder / "sensors-loops.png")
    margins_figure(designs, folder / "sensors-margins.png")
    time_figure(designs, passive, band, folder / "sensors-time.png")
    budget_figure({d.method: d.budget for d in designs if d.budget is not None}, folder / "sensors-budget.png")


def defaults_figure(designs: Sequence[SensorDesign], passive: Response, band: Band, path: Path) -> None:
    """The move's settling (slowest signal, in the study's band) over the passive table's and the peak command
    over ``max_force``: each design as ``isolator controller`` makes it by default and, for the searched
    methods, with the method's own weights (``search=False``)."""
    if not designs:
        return
    values = list(passive.with_band(band).settling_time.values())
    reference = None if any(v is None for v in values) else max(v for v in values if v is not None)
    rows: list[tuple[str, float | None, float, str]] = [("passive", reference, 0.0, "0.3")]
    for d in designs:
        if "search" in d.controller.settings:
            rows.append((f"{d.method}, own weights", d.unsearched, d.unsearched_share, "0.65"))
        rows.append((f"{d.method}, default" + (" (searched)" if "search" in d.controller.settings else ""),
                     d.settling_time_max, d.force_share, "C0"))
    fig, axes = plt.subplots(1, 2, figsize=(13, 0.55 * len(rows) + 1.8), layout="constrained", sharey=True)
    y = np.arange(len(rows))
    for i, (_, value, share, color) in enumerate(rows):
        ratio = math.nan if value is None or not reference else value / reference
        axes[0].barh(i, ratio if math.isfinite(ratio) else 0.0, color=color)
        axes[0].annotate("did not settle" if value is None else f"{ratio:.3f} ({value:.3g} s)",
                         (ratio if math.isfinite(ratio) else 0.0, i), xytext=(4, 0), textcoords="offset points",
                         va="center", fontsize=8)
        axes[1].barh(i, share, color=color)
        axes[1].annotate(f"{share:.2f}", (share, i), xytext=(4, 0), textcoords="offset points", va="center",
                         fontsize=8)
    axes[0].set_xlim(0.0, 1.3)
    axes[0].set_yticks(y, [r[0] for r in rows])
    axes[0].invert_yaxis()
    axes[0].set_xlabel("settling of the move / the passive table's [-] (slowest signal)")
    axes[0].set_title(f"settling: the passive table's {fmt(reference)} s is 1")
    limit = max((d.controller.settings.get("search", {}).get("force_share", math.nan) for d in designs),
                default=math.nan)
    if math.isfinite(limit):
        axes[1].axvline(limit, color="C3", ls="--", lw=1.0, label=f"the search's limit ({limit:.0%})")
        axes[1].legend(fontsize=8, loc="lower right")
    axes[1].set_xlabel("peak command / max_force [-] (largest over the actuators)")
    axes[1].set_title("force used")
    for ax in axes:
        ax.grid(True, axis="x", alpha=0.3)
    fig.suptitle("Default sensor-based designs (grey: the methods' own weights, unsearched)")
    save_figure(fig, path)


def margins_figure(designs: Sequence[SensorDesign], path: Path) -> None:
    """Multiloop disk margin and the smallest loop-at-a-time phase and gain margins along the travel, per
    design (a gain margin unlimited everywhere is not drawn)."""
    if not designs:
        return
    cases = designs[0].travel
    index = int(np.argmax(np.ptp([c.positions for c in cases], axis=0)))
    name = cases[0].carriages[index]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2), layout="constrained")
    for d in designs:
        x = [c.positions[index] for c in d.travel]
        axes[0].plot(x, [c.margin("disk_margin") for c in d.travel], marker="o", label=d.method)
        axes[1].plot(x, [c.margin("phase_margin") for c in d.travel], marker="o", label=d.method)
        axes[2].plot(x, [c.margin("gain_margin") for c in d.travel], marker="o", label=d.method)
    for ax, title, unit in zip(axes, ("multiloop disk margin at the actuators", "smallest loop-at-a-time phase "
                                      "margin", "smallest loop-at-a-time gain margin"), ("[-]", "[deg]", "[x]"),
                               strict=True):
        ax.set_title(title)
        ax.set_xlabel(f"{name} position [m]")
        ax.set_ylabel(f"{title.split(' at ')[0]} {unit}")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Margins of the sensor-based designs along the travel (nominal isolators, actuator lag and "
                 "sampling included)")
    save_figure(fig, path)


def loops_figure(designs: Sequence[SensorDesign], scenario: Scenario, path: Path) -> None:
    """Floor-to-sensor transmissibility of the first vertical sensor, and the largest singular values of the
    sensitivity and the complementary sensitivity at the sensors, per design."""
    if not designs:
        return
    sensors = scenario.sensors
    j = next((k for k, s in enumerate(sensors) if abs(s.direction[2]) > 0.9), 0)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4), layout="constrained")
    f = designs[0].loops.frequency_hz
    axes[0].loglog(f, designs[0].loops.passive[:, j], color="0.2", lw=1.8, label="passive")
    for d in designs:
        axes[0].loglog(f, d.loops.transmissibility[:, j], label=d.method)
        axes[1].semilogx(f, d.loops.sensitivity, label=d.method)
        axes[2].loglog(f, d.loops.complementary, label=d.method)
    axes[0].set_title(f"floor to sensor {sensors[j].name} ({sensors[j].quantity})")
    axes[0].set_ylabel("|T| [-] (floor motion along the sensor, same quantity)")
    axes[1].set_title("output sensitivity at the sensors")
    axes[1].set_ylabel("largest singular value of S [-]")
    axes[2].set_title("complementary sensitivity at the sensors")
    axes[2].set_ylabel("largest singular value of T [-]")
    for ax in axes:
        ax.set_xlabel("frequency [Hz]")
        ax.axhline(1.0, color="0.6", lw=0.8, ls="--")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"Output feedback from the sensors ({scenario.name}, carriages mid-travel, "
                 f"{designs[0].controller.sample_rate:g} Hz)")
    save_figure(fig, path)


def time_figure(designs: Sequence[SensorDesign], passive: Response, band: Band, path: Path) -> None:
    """The six table signals in the passive run and with each sensor-based design, with the band."""
    if not designs:
        return
    fig, axes = plt.subplots(2, 3, figsize=(14, 7), sharex=True, layout="constrained")
    for i, sig in enumerate(SIGNALS):
        ax = axes[i // 3, i % 3]
        scale, unit = micro_unit(sig)
        ax.plot(passive.t, passive.signal(sig) * scale, color="0.35", lw=1.2, label="passive")
        for d in designs:
            ax.plot(d.response.t, d.response.signal(sig) * scale, lw=1.0, label=d.method)
        half = band.half_widths[i] * scale if band.half_widths is not None else None
        if half is not None and passive.final is not None:
            for sign in (-1, 1):
                ax.axhline(passive.final[i] * scale + sign * half, color="0.6", lw=0.7, ls="--")
        ax.set_title(sig)
        ax.set_ylabel(f"{sig} [{unit}]")
        ax.grid(True, alpha=0.3)
        if i >= 3:
            ax.set_xlabel("time [s]")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("The carriage move with output feedback from the sensors (dashed: the settling band)")
    save_figure(fig, path)


def sensor_report(designs: Sequence[SensorDesign], left_out: dict[str, str] | None = None) -> list[str]:
    """The report's section on the sensor-based designs (markdown lines)."""
    skipped = [f"- {method} left out: {why}" for method, why in (left_out or {}).items()]
    if not designs:
        return ["## Output feedback from the sensors", "", *skipped, ""] if skipped else []
    lines = ["## Output feedback from the sensors (what the machine can run)", "",
             f"Discrete controllers from the scenario's [[sensors]] to its [[actuators]] at "
             f"{designs[0].controller.sample_rate:g} Hz, as `isolator controller` exports them; the move simulated "
             "with each in the loop exactly as the C runs it (noise-free sensors).", "",
             *table_header(["design", "states", "settling [s]", "peak force [N]", "RMS force [N]", "peak |S|",
                            "peak |T|", "noise: worst table RMS", "noise: RMS force [N]"])]
    for d in designs:
        worst = max(SIGNALS, key=lambda s: d.noise.table_rms[s] * micro_unit(s)[0])
        scale, unit = micro_unit(worst)
        lines.append(table_row([d.method, d.controller.states, fmt(d.settling_time_max), fmt(d.peak_force),
                                fmt(d.rms_force), fmt(float(np.max(d.loops.sensitivity))),
                                fmt(float(np.max(d.loops.complementary))),
                                f"{worst} {d.noise.table_rms[worst] * scale:.3g} {unit}",
                                fmt(float(np.max(d.noise.force_rms)))]))
    lines += ["", "Margins along the travel (nominal isolators; the check over the travel's extremes and middle is in "
              "results.json under each design's `robustness`):", "",
              *table_header(["design", "least multiloop disk margin", "least phase margin [deg]",
                             "largest spectral radius", "robustness check"])]
    for d in designs:
        lines.append(table_row([d.method, fmt(min(c.margin("disk_margin") for c in d.travel)),
                                fmt(min(c.margin("phase_margin") for c in d.travel)),
                                f"{max(c.spectral_radius for c in d.travel):.5f}",
                                "stable in all " + str(d.robustness["cases_checked"]) + " cases"
                                if d.robustness["stable"] else "UNSTABLE somewhere"]))
    lines += _search_report(designs)
    lines += ["", *skipped, "", "The noise columns: the stationary RMS that the sensors' own noise (their `noise`, "
              "per sample; a `noise_psd` spectrum is counted in the error budget below, not here) causes through "
              "the sampled loop, exact (discrete Lyapunov equation), carriages mid-travel.", ""]
    budgets = {d.method: d.budget for d in designs if d.budget is not None}
    return lines + (budget_section(budgets) if budgets else [])


def _search_report(designs: Sequence[SensorDesign]) -> list[str]:
    """The weights the search chose against the methods' own defaults (markdown lines; none without a search)."""
    searched = [d for d in designs if "search" in d.controller.settings]
    if not searched:
        return []
    passive = searched[0].controller.settings["search"]["passive_settling"]
    lines = ["", f"Default weights chosen by a search (`controllers.feedback.output_tuning`): the move's settling "
             f"in the passive band against the passive table's {fmt(passive)} s, the peak command within "
             f"{searched[0].controller.settings['search']['force_share']:.0%} of `max_force`, the margins over the "
             "travel kept:", "",
             *table_header(["design", "weights chosen (per world axis x, y, z)", "settling / passive",
                            "method's own default / passive", "peak command / max_force",
                            "own default's peak command / max_force", "candidates"])]
    for d in searched:
        search = d.controller.settings["search"]
        chosen = ", ".join(f"{k} " + (", ".join(f"{x:.3g}" for x in v) if isinstance(v, list) else f"{v:.3g}")
                           for k, v in search["chosen"].items()) or "the method's own"
        ratio = None if d.settling_time_max is None else d.settling_time_max / passive
        own = None if d.unsearched is None else d.unsearched / passive
        lines.append(table_row([d.method, chosen, fmt(ratio, ".3f"), fmt(own, ".3f"), fmt(d.force_share, ".2f"),
                                fmt(d.unsearched_share, ".2f"), search["candidates"]]))
    return [*lines, "", "`sensors-defaults.png` draws the same against the passive table."]


check_public(globals())
