"""The control study's error budget (:mod:`studies.control_sensors`): what each sensor-based design buys and costs
in random motion at the tool.

For each exported controller the study compares the passive error budget with the closed loop's
(:func:`isolator.analysis.budget.error_budget`, the table parked with its carriages at their start, the same band
for both: 0.1 Hz to just below half the controller's rate), at the tool (the first ``[[points]]`` entry, or the
mass centre, ``table``): the total RMS per axis, the part the sensors' own noise adds in the closed loop, and
where that noise sits (the frequency below which half its square lies). The controller pulls the table towards
inertial rest at its isolation modes, and feeds back its sensors' noise, which geophones and accelerometers have
most of at low frequency: the budget shows both.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from isolator.analysis.budget import (
    AXES,
    ErrorBudget,
    budget_band,
    budget_point_names,
    error_budget,
    has_random_sources,
)
from isolator.errors import IsolatorError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.ground import Ground
from isolator.scenario.random_sources import vc_spectrum
from isolator.simulation.discrete_controller import DiscreteController

from .figures import save_figure
from .reporting import table_header, table_row

__all__ = ["NM", "DesignBudget", "budget_figure", "budget_section", "design_budget", "on_floor"]

#: metres to nanometres
NM = 1e9
#: the prefix of a sensor's noise among a budget's sources
_SENSOR = "sensor:"


def on_floor(scenario: Scenario, vc: str, key: str = "floor") -> Scenario:
    """``scenario`` on a floor at the limit of the vibration criterion ``vc`` ("VC-A" to "VC-G"): its
    ``[ground.spectrum]`` replaced (``vc = ...`` of the scenario format), all else as it was.

    Raises
    ------
    ScenarioError
        An unknown class, naming ``key``.
    """
    spectrum = vc_spectrum(vc, key)
    return replace(scenario, ground=replace(scenario.ground or Ground(), spectrum=spectrum))


@dataclass(frozen=True)
class DesignBudget:
    """One design's error budget at the tool, passive and closed loop, in one band.

    Attributes
    ----------
    point : str
        The tool: the first ``[[points]]`` entry, or ``table`` (the mass centre).
    passive, closed : ErrorBudget or None
        Displacement budgets [m] at ``point`` (None: no budget, see ``note``).
    note : str
        Why there is no budget ("" when there is).
    """

    point: str
    passive: ErrorBudget | None
    closed: ErrorBudget | None
    note: str = ""

    @property
    def available(self) -> bool:
        """Whether both budgets are there."""
        return self.passive is not None and self.closed is not None

    def sensor_psd(self) -> np.ndarray:
        """(3, nf) the closed loop's PSD at the tool from the sensors' noise alone [m^2/Hz]."""
        if self.closed is None:
            raise ValueError("sensor_psd: no closed-loop budget")
        parts = [k for k, s in enumerate(self.closed.sources) if s.startswith(_SENSOR)]
        return np.asarray(self.closed.psd[0][:, parts, :].sum(axis=1))

    def sensor_rms(self) -> np.ndarray:
        """(3,) RMS of the sensors' noise at the tool per axis [m]."""
        if self.closed is None:
            raise ValueError("sensor_rms: no closed-loop budget")
        return np.sqrt(np.trapezoid(self.sensor_psd(), self.closed.frequency, axis=-1))

    def sensor_half_frequency(self) -> np.ndarray:
        """(3,) the frequency [Hz] below which half the square of the sensors' noise at the tool lies, per axis
        (NaN without sensor noise)."""
        if self.closed is None:
            raise ValueError("sensor_half_frequency: no closed-loop budget")
        psd, f = self.sensor_psd(), self.closed.frequency
        steps = 0.5 * (psd[:, 1:] + psd[:, :-1]) * np.diff(f)
        cumulative = np.concatenate([np.zeros((3, 1)), np.cumsum(steps, axis=1)], axis=1)
        out = np.full(3, np.nan)
        for j in range(3):
            if cumulative[j, -1] > 0:
                out[j] = float(np.interp(0.5 * cumulative[j, -1], cumulative[j], f))
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the point, the band [Hz], per axis the passive and closed-loop RMS and the sensors' noise
        part [m], or the note."""
        if self.passive is None or self.closed is None:
            return {"point": self.point, "note": self.note}
        sensor = self.sensor_rms()
        return {"point": self.point, "band": list(self.closed.band),
                "axes": {a: {"passive_rms": float(self.passive.rms[0, j]), "closed_rms": float(self.closed.rms[0, j]),
                             "sensor_noise_rms": float(sensor[j])} for j, a in enumerate(AXES)}}


def design_budget(scenario: Scenario, controller: DiscreteController) -> DesignBudget:
    """The passive and closed-loop displacement budgets at the tool, in the closed loop's default band.

    A scenario without a random source on the passive table (no ``[ground.spectrum]``, ``[[disturbances]]`` or
    actuator ``noise_psd``), or a loop the budget refuses, gives a :class:`DesignBudget` without budgets whose
    ``note`` says why.
    """
    point = budget_point_names(scenario)[0]
    if not has_random_sources(scenario):
        return DesignBudget(point, None, None, "the scenario has no random source on the passive table: the budget "
                            "needs a floor spectrum ([ground.spectrum], or --floor VC-D for a floor at a vibration "
                            "criterion), [[disturbances]] or an actuator's noise_psd (paper-table-3-2-budget has "
                            "all three)")
    band = budget_band(None, controller)
    try:
        passive = error_budget(scenario, points=[point], band=band)
        closed = error_budget(scenario, controller, points=[point], band=band)
    except IsolatorError as exc:
        return DesignBudget(point, None, None, str(exc))
    return DesignBudget(point, passive, closed)


def _shown(budgets: dict[str, DesignBudget]) -> list[tuple[str, DesignBudget, ErrorBudget, ErrorBudget]]:
    """(method, its budget, passive, closed loop) of the designs that have both budgets."""
    return [(m, b, b.passive, b.closed) for m, b in budgets.items() if b.passive is not None and b.closed is not None]


def budget_figure(budgets: dict[str, DesignBudget], path: Path) -> None:
    """``sensors-budget.png``: the total RMS at the tool per axis, passive and with each design, the sensors'
    noise part hatched (top left); per axis the ASD passive and closed loop, the sensors' noise part dashed."""
    shown = _shown(budgets)
    if not shown:
        return
    point, passive = shown[0][1].point, shown[0][2]
    fig, axes = plt.subplots(2, 2, figsize=(13, 9), layout="constrained")
    bars = axes[0, 0]
    width = 0.8 / (len(shown) + 1)
    x = np.arange(len(AXES))
    bars.bar(x - 0.4 + width / 2, passive.rms[0] * NM, width, color="0.35", label="passive")
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, (method, b, _, closed) in enumerate(shown):
        at = x - 0.4 + (k + 1.5) * width
        colour = colours[k % len(colours)]
        bars.bar(at, closed.rms[0] * NM, width, color=colour, label=f"{method}: closed loop, total")
        bars.bar(at, b.sensor_rms() * NM, width * 0.6, color="white", edgecolor=colour, hatch="///",
                 label=f"{method}: of which its sensors' noise")
    bars.set_xticks(x, list(AXES))
    bars.set_xlabel("axis (world frame)")
    bars.set_yscale("log")  # the sensors' noise is often orders of magnitude below the total
    bars.set_ylabel("displacement RMS [nm]")
    bars.set_title(f"random motion at {point}, total per axis")
    bars.set_ylim(top=float(max(np.max(p.rms) for _, _, p, _ in shown)) * NM * 30)  # room for the legend above
    bars.legend(fontsize=7, ncol=2, loc="upper center")
    bars.grid(True, axis="y", alpha=0.3)
    for j, ax in enumerate((axes[0, 1], axes[1, 0], axes[1, 1])):
        ax.loglog(passive.frequency, np.sqrt(passive.total_psd[0, j]) * NM, color="0.2", lw=1.8, label="passive")
        for k, (method, b, _, closed) in enumerate(shown):
            colour = colours[k % len(colours)]
            ax.loglog(closed.frequency, np.sqrt(closed.total_psd[0, j]) * NM, color=colour, lw=1.2,
                      label=f"{method}: closed loop")
            ax.loglog(closed.frequency, np.sqrt(b.sensor_psd()[j]) * NM, color=colour, lw=1.0, ls="--",
                      label=f"{method}: its sensors' noise")
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel(f"{AXES[j]}: displacement ASD [nm/√Hz]")
        ax.set_title(f"{point} along {AXES[j]}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    low, high = passive.band
    fig.suptitle(f"Error budget at {point}: passive against each sensor-based design ({low:g} Hz to "
                 f"{high:.4g} Hz, carriages at their start)")
    save_figure(fig, path)


def budget_section(budgets: dict[str, DesignBudget]) -> list[str]:
    """The report's section on the error budget (Markdown lines; the note when there is none)."""
    lines = ["## Error budget at the tool: what each design buys and what its sensors' noise costs", ""]
    shown = _shown(budgets)
    if not shown:
        notes = sorted({b.note for b in budgets.values()})
        return [*lines, *(f"No budget: {n}." for n in notes), ""]
    first = shown[0][3]
    low, high = first.band
    lines += [f"Random displacement at `{shown[0][1].point}` while the table stands still (`isolator budget`, "
              f"carriages at their start, {low:g} Hz to {high:.4g} Hz for both: the closed loop's band ends just "
              "below half the controller's rate), passive and with each exported controller in the loop; sources: "
              f"{', '.join(first.sources)}. 'Through the loop' is the closed loop without its sensors' "
              "noise (the floor, forces and amplifiers it sees); 'half below' is the frequency below which half "
              "the square of the sensors' noise at the tool lies. Figure: `sensors-budget.png`.", "",
              *table_header(["design", "axis", "passive [nm]", "closed loop [nm]", "through the loop [nm]",
                             "sensors' noise [nm]", "half below [Hz]"])]
    for method, b, passive, closed in shown:
        sensor, half = b.sensor_rms(), b.sensor_half_frequency()
        for j, a in enumerate(AXES):
            rest = np.sqrt(max(closed.rms[0, j] ** 2 - sensor[j] ** 2, 0.0))
            lines.append(table_row([method, a, f"{passive.rms[0, j] * NM:.4g}", f"{closed.rms[0, j] * NM:.4g}",
                                    f"{rest * NM:.4g}", f"{sensor[j] * NM:.3g}",
                                    "n/a" if np.isnan(half[j]) else f"{half[j]:.3g}"]))
    lines += ["", *(f"- {m}: no budget: {b.note}." for m, b in budgets.items() if not b.available), ""]
    return lines


check_public(globals())
