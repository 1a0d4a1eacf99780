"""The trade-off study's error budget (:mod:`studies.tradeoff`): per design the passive budget's displacement RMS
at the tool on the scenario's floor, its figure ``budget.png`` and its section of the report.

The tool is the scenario's first ``[[points]]`` entry (its mass centre, ``table``, when it has none); each
design's value is the largest of its x, y and z RMS there (:func:`isolator.analysis.budget.error_budget` of the
design's table parked with its carriages at their start, default band 0.1 Hz to 1 kHz, every random source of
the scenario: floor, force disturbances, actuators' noise), the sweep's ``budget:<point>:<axis>`` columns
computed in its workers beside the transient runs.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from isolator.analysis.budget import AXES, DEFAULT_BAND, budget_point_names, has_random_sources
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario

from .figures import save_figure
from .reporting import fmt, table_header, table_row
from .tradeoff_report import scatter_designs
from .tradeoff_results import TradeoffStudy

__all__ = ["NM", "budget_report", "budget_tool", "plot_budget", "worst_axis"]

#: metres to nanometres
NM = 1e9


def budget_tool(scenario: Scenario) -> str | None:
    """The point the study budgets (the first ``[[points]]`` entry, or ``table``), None when the scenario has no
    random source (no ``[ground.spectrum]``, ``[[disturbances]]`` or actuator ``noise_psd``)."""
    return budget_point_names(scenario)[0] if has_random_sources(scenario) else None


def worst_axis(rms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per row of ``rms`` (designs, 3: x, y, z) [m] the largest value and its axis (NaN and "" for a row with
    a NaN: a design without a budget)."""
    rms = np.asarray(rms, dtype=float)
    known = np.all(np.isfinite(rms), axis=1)
    at = np.argmax(np.where(np.isfinite(rms), rms, -np.inf), axis=1)
    value = np.where(known, rms[np.arange(rms.shape[0]), at], np.nan)
    axis = np.array([AXES[a] if ok else "" for a, ok in zip(at, known, strict=True)], dtype=object)
    return value, axis


def plot_budget(study: TradeoffStudy) -> None:
    """``budget.png``: the time figure against the budget's RMS at the tool [nm] (left) and against the
    transmissibility's resonance peak (right), each with its Pareto front and the scenario's design."""
    fig, axes = plt.subplots(1, 2, figsize=(15, 6), constrained_layout=True)
    time = ("total time of the sequence [s]" if study.sequence else
            f"largest settling time after the carriages stop [s] (band: {study.band.how()})")
    panels = ((axes[0], study.budget_rms * NM, study.budget_pareto(),
               f"error budget at {study.budget_point}: displacement RMS, worst of x, y, z [nm]"),
              (axes[1], study.peak, study.peak_pareto(), "resonance peak of the transmissibility, worst of x, y, "
               "z [m/m]"))
    for ax, values, front, label in panels:
        # the size scale lower right: the front and the best designs are lower left
        scatter_designs(study, ax, study.settling_time, front, values, label, scale_at="lower right")
        ax.set_xlabel(time)
        ax.legend(loc="best", fontsize=8)
    low, high = DEFAULT_BAND
    axes[0].set_title(f"random motion at the tool ({low:g} Hz to {high:g} Hz, passive, on the scenario's floor)")
    axes[1].set_title("amplification at the table's modes")
    fig.suptitle(f"{study.scenario.name}: {'total time' if study.sequence else 'settling'} against the error "
                 "budget and the resonance peak (lower left is better)")
    save_figure(fig, study.folder / "budget.png", dpi=110)


def budget_report(study: TradeoffStudy) -> list[str]:
    """The report's section on the error budget (Markdown lines); without a random source, why there is none."""
    if study.budget_point is None:
        return ["## Error budget at the tool", "",
                "The scenario has no random source, so the study has no error budget: the budget needs a floor "
                "spectrum (`[ground.spectrum]`, or `vc = \"VC-C\"` for a floor at a vibration criterion), "
                "`[[disturbances]]` or an actuator's `noise_psd` (`paper-table-3-2-budget` has all three).", ""]
    low, high = DEFAULT_BAND
    lines = ["## Error budget at the tool", "",
             f"The random motion at `{study.budget_point}` "
             f"({'the first [[points]] entry' if study.scenario.points else 'the mass centre: no [[points]]'}) "
             f"while the table stands still: each design's passive error budget (`isolator budget`), displacement "
             f"RMS from {low:g} Hz to {high:g} Hz, absolute, the largest of the x, y and z values (the "
             "`budget_axis` column of `designs.csv` says which), every random source of the scenario (its floor, "
             "force disturbances and actuators' noise), the table parked with its carriages at their start "
             "(the sweep's `budget:<point>:<axis>` columns, computed in its workers beside the runs).", "",
             "![budget](budget.png)", ""]
    nominal = study.nominal()
    if nominal is not None and np.isfinite(study.budget_rms[nominal]):
        lines.append(f"The scenario's design: {study.budget_rms[nominal] * NM:.4g} nm RMS along "
                     f"{study.budget_axis[nominal]}.")
    finite = np.where(np.isfinite(study.budget_rms), study.budget_rms, np.inf)
    if np.isfinite(finite).any():
        at = np.unravel_index(int(np.argmin(finite)), finite.shape)
        lines.append(f"The quietest design: {study.budget_rms[at] * NM:.4g} nm along {study.budget_axis[at]} with "
                     f"stiffness x{study.stiffness[at[0]]:.3g}, damping x{study.damping[at[1]]:.3g} (settling "
                     f"{fmt(float(study.settling_time[at]), '.3f')} s, resonance peak {study.peak[at]:.3g}).")
    lines += ["", f"Designs no other beats in both the {study.time_label} and the budget, by increasing time:", "",
              *table_header(["stiffness x", "damping x", "time [s]", "budget RMS [nm]", "axis",
                             "resonance peak", f"transmissibility at {study.reference_hz:g} Hz"])]
    lines += [table_row([f"{study.stiffness[i]:.3g}", f"{study.damping[j]:.3g}", f"{study.settling_time[i, j]:.3f}",
                         f"{study.budget_rms[i, j] * NM:.4g}", study.budget_axis[i, j], f"{study.peak[i, j]:.3g}",
                         f"{study.transmissibility[i, j]:.3g}"]) for i, j in study.budget_pareto()] \
        or ["| (none) | | | | | | |"]
    lines += ["", "The budget and the resonance peak need not agree: the budget weighs each frequency by the floor's "
              "and the forces' spectra, so a design with a low peak can still pass more of the floor where the "
              "floor is loud.", ""]
    return lines


check_public(globals())
