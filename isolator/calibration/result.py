"""What a calibration gives: the fitted parameters with their uncertainty, the fitted scenario, the
experiments' residuals and curves, the modes before and after (``docs/scenario-format.md`` fixes the JSON)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from isolator.calibration.definition import Calibration
from isolator.calibration.fit import Fit
from isolator.calibration.goodness import Goodness
from isolator.scenario.definitions import Scenario
from isolator.scenario.output_files import save_figure_file
from isolator.scenario.writing import write_toml

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["CalibrationResult", "Curves", "ParameterEstimate"]


@dataclass(frozen=True)
class ParameterEstimate:
    """One fitted parameter [SI].

    Attributes
    ----------
    initial, value, std : float
        The scenario's value, the fitted value and its standard deviation.
    ci95 : tuple of float
        The 95 % interval.
    bounds : tuple of float
        The bounds the fit stayed in.
    """

    initial: float
    value: float
    std: float
    ci95: tuple[float, float]
    bounds: tuple[float, float]

    def to_dict(self) -> dict[str, Any]:
        """``{initial, value, std, ci95: [low, high]}`` (``std`` null for a parameter the records do not fix,
        its ``ci95`` then its bounds)."""
        return {"initial": self.initial, "value": self.value, "std": self.std if math.isfinite(self.std) else None,
                "ci95": list(self.ci95)}


@dataclass(frozen=True)
class Curves:
    """One experiment's measured data against the nominal and the fitted model (for the figure).

    Attributes
    ----------
    kind : {"floor", "move"}
    x : ndarray (N,)
        Frequencies [Hz] (floor) or times [s] (move).
    measured, nominal, fitted : ndarray (sensors, inputs, N) complex (floor) or (sensors, N) (move)
    coherence : ndarray (sensors, N) or None
        Floor: each table sensor's multiple coherence with the floor sensors.
    outputs, inputs : tuple of str
        The table sensors and (floor) the floor sensors.
    units : tuple of str
        Each table sensor's unit.
    """

    kind: str
    x: np.ndarray
    measured: np.ndarray
    nominal: np.ndarray
    fitted: np.ndarray
    coherence: np.ndarray | None
    outputs: tuple[str, ...]
    inputs: tuple[str, ...] = ()
    units: tuple[str, ...] = ()


@dataclass(frozen=True)
class CalibrationResult:
    """A calibration's outcome (:func:`isolator.calibrate`).

    Attributes
    ----------
    calibration : Calibration
    parameters : dict of str to ParameterEstimate
        By fitted name, in the calibration's order.
    scenario : Scenario
        The fitted scenario (the calibrated model).
    identifiable : bool
    unidentifiable : list of list of str
        The parameters of each direction the records cannot resolve.
    correlation : ndarray (n, n)
        In the order of ``parameters``.
    experiments : dict of str to dict
        Per experiment: ``kind``, ``residual_before`` and ``residual_after`` (RMS of the noise-weighted
        residuals, about 1 at a fit within the noise), ``points`` (residuals), ``fit_ok``, ``fit_ratio`` and
        ``fit_limit`` (the goodness-of-fit test: :mod:`isolator.calibration.goodness`), ``worst_sensor`` (the
        table sensor whose channel misfits most).
    modes : dict
        ``nominal`` and ``fitted``: ``frequencies_hz`` and ``damping_ratios`` at the scenario's start.
    fit : Fit
    curves : dict of str to Curves
    fitted_data : dict
        The fitted scenario's keys (what :meth:`write_scenario` writes).
    goodness : dict of str to Goodness
        Each experiment's goodness of fit, by name.
    """

    calibration: Calibration
    parameters: dict[str, ParameterEstimate]
    scenario: Scenario
    identifiable: bool
    unidentifiable: list[list[str]]
    correlation: np.ndarray
    experiments: dict[str, dict[str, Any]]
    modes: dict[str, dict[str, list[float]]]
    fit: Fit
    curves: dict[str, Curves] = field(default_factory=dict, repr=False)
    fitted_data: dict[str, Any] = field(default_factory=dict, repr=False)
    goodness: dict[str, Goodness] = field(default_factory=dict, repr=False)

    @property
    def fit_ok(self) -> bool:
        """Whether the fit explains every experiment's record within its noise (the goodness-of-fit test)."""
        return all(g.ok for g in self.goodness.values())

    def to_dict(self) -> dict[str, Any]:
        """The contract's JSON: ``parameters``, ``identifiable``, ``unidentifiable``, ``correlation``,
        ``experiments``, ``modes``; with ``fit_ok``, ``residual_variance`` and ``evaluations``."""
        return {
            "parameters": {n: e.to_dict() for n, e in self.parameters.items()},
            "identifiable": self.identifiable,
            "fit_ok": self.fit_ok,
            "unidentifiable": [list(g) for g in self.unidentifiable],
            "correlation": [[float(v) for v in row] for row in self.correlation],
            "experiments": self.experiments,
            "modes": self.modes,
            "residual_variance": self.fit.residual_variance,
            "evaluations": self.fit.evaluations,
        }

    def write_scenario(self, path: str | Path) -> Path:
        """Write the fitted scenario (the scenario file with the fitted values; relative files made absolute)."""
        return write_toml(self.fitted_data, path)

    def summary(self) -> str:
        """A text table of the parameters, the residuals and the modes."""
        lines = [f"{'parameter':<32} {'initial':>11} {'fitted':>11} {'std':>10}  95 % interval"]
        for n, e in self.parameters.items():
            lines.append(f"{n:<32} {e.initial:>11.5g} {e.value:>11.5g} {e.std:>10.3g}  "
                         f"[{e.ci95[0]:.5g}, {e.ci95[1]:.5g}]")
        for n, x in self.experiments.items():
            verdict = "within the noise" if x["fit_ok"] else f"MISFIT, {x['worst_sensor']} most"
            lines.append(f"experiment {n} ({x['kind']}): weighted RMS residual {x['residual_before']:.4g} -> "
                         f"{x['residual_after']:.4g}; residual variance {x['fit_ratio']:.4g} times the noise's "
                         f"(limit {x['fit_limit']:.4g}: {verdict})")
        nominal, fitted = self.modes["nominal"], self.modes["fitted"]
        lines.append("modes [Hz]: " + ", ".join(f"{a:.4g} -> {b:.4g}" for a, b in
                                                zip(nominal["frequencies_hz"], fitted["frequencies_hz"], strict=False)))
        if not self.identifiable:
            lines.append("NOT identifiable: " + "; ".join(", ".join(g) for g in self.unidentifiable))
        return "\n".join(lines)

    def plot(self, path: str | Path | None = None) -> Figure:
        """The figure (:func:`isolator.calibration.figure.calibration_figure`); saved when ``path`` is given."""
        from isolator.calibration.figure import calibration_figure

        fig = calibration_figure(self)
        if path is not None:
            save_figure_file(fig, path, dpi=110)
        return fig
