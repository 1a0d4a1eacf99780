"""``isolator.calibrate``: read a calibration, its records, fit, and gather the result."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from isolator.analysis.linear import linearise
from isolator.analysis.modes import modes
from isolator.calibration.definition import Calibration, load_calibration
from isolator.calibration.experiments import FloorExperiment, MoveExperiment, prepare
from isolator.calibration.fit import Fit, fit_parameters
from isolator.calibration.goodness import Goodness, goodness_of_fit, misfit_message
from isolator.calibration.records import Record, read_record
from isolator.calibration.result import CalibrationResult, Curves, ParameterEstimate
from isolator.errors import MisfitError, ParameterError, ScenarioError, UnidentifiableError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.reader import scenario_from_dict
from isolator.scenario.writing import scenario_data, set_parameter

__all__ = ["calibrate", "read_records"]


def read_records(calibration: Calibration) -> dict[str, Record]:
    """Each experiment's record, by experiment name (every problem one line naming the file)."""
    names = [s.name for s in calibration.scenario.sensors]
    uff = {s.name: s.uff for s in calibration.scenario.sensors if s.uff is not None}
    out = {}
    for e in calibration.experiments:
        try:
            out[e.name] = read_record(e.file, names, uff)
        except ParameterError as exc:
            raise ScenarioError(f"{e.key}: {exc}") from None
    return out


def calibrate(
    calibration: str | Path | Calibration,
    fit: Sequence[str] | None = None,
    allow_unidentifiable: bool = False,
    progress: Callable[[str], None] | None = None,
    jacobian: str = "model",
    accept_misfit: bool = False,
) -> CalibrationResult:
    """Fit a scenario's parameters to measured records.

    Parameters
    ----------
    calibration : str or Path or Calibration
        A calibration file (``docs/scenario-format.md``, "Calibration from measured records") or one read
        with :func:`isolator.calibration.load_calibration`.
    fit : sequence of str, optional
        Fit only these of the file's ``fit`` names (the others keep the scenario's values).
    allow_unidentifiable : bool
        Give the fit even when the records cannot tell some parameters apart (``identifiable`` False).
    progress : callable, optional
        Called with a line per model evaluation.
    jacobian : {"model", "differences"}
        The fit's Jacobian: the model's (floor: exact derivatives; move: the perturbed runs in one batch of SIMD
        lanes), or scipy's forward differences run by run (a baseline for ``benchmarks/bench_calibration.py``).
    accept_misfit : bool
        Give the fit (``fit_ok`` False, and a warning naming the misfit) even when it does not explain the
        records: an experiment's weighted residual variance beyond its chi-square limit
        (:mod:`isolator.calibration.goodness`).

    Returns
    -------
    CalibrationResult
        The fitted parameters with their standard deviations, 95 % intervals and correlations, each
        experiment's data and curves, the fitted scenario and its modes.

    Raises
    ------
    ScenarioError
        A bad calibration file or record (one line naming the file, key, line or column).
    ParameterError
        ``calibration`` of a wrong type, or a ``fit`` name the file does not fit.
    UnidentifiableError
        The records cannot tell some fitted parameters apart (they are named), unless ``allow_unidentifiable``.
    MisfitError
        The fit does not explain some experiment's record (the experiment, its ratio and the likely cause are
        named; the refused result is the error's ``result``), unless ``accept_misfit``.

    Examples
    --------
    >>> from isolator import calibrate
    >>> result = calibrate("table-3-2")  # the bundled example: a file's path works the same
    >>> z = result.parameters["isolators[*].stiffness.z"]
    >>> z.initial, round(z.value, -3)  # N/m: the datasheet's and the fitted value (the truth: 6.555e5)
    (570000.0, 656000.0)
    """
    if isinstance(calibration, str | Path):
        calibration = load_calibration(calibration)
    elif not isinstance(calibration, Calibration):
        raise ParameterError(f"calibration: must be a calibration file's path or a Calibration, got "
                             f"{type(calibration).__name__}")
    if fit is not None:
        calibration = _restricted(calibration, fit)
    experiments = prepare(calibration, read_records(calibration))
    outcome = fit_parameters(calibration, experiments, progress, jacobian)
    if outcome.unidentifiable and not allow_unidentifiable:
        groups = "; ".join(" with ".join(g) for g in outcome.unidentifiable)
        raise UnidentifiableError(f"calibrate: the records cannot tell apart {groups} (fit fewer parameters, add "
                                  "experiments that separate them, or --allow-unidentifiable)", outcome.unidentifiable)
    data, scenario = _fitted(calibration, outcome.values)
    p0, p1 = calibration.vector(), calibration.vector(outcome.values)
    curves = {e.name: _curves(e, p0, p1) for e in experiments}
    goodness = _goodness(calibration, experiments, outcome, curves)
    parameters = {f.name: ParameterEstimate(f.initial, float(v), float(s), (float(lo), float(hi)), f.bounds)
                  for f, v, s, (lo, hi) in zip(calibration.parameters, outcome.values, outcome.std, outcome.ci95,
                                               strict=True)}
    result = CalibrationResult(
        calibration=calibration,
        parameters=parameters,
        scenario=scenario,
        identifiable=not outcome.unidentifiable,
        unidentifiable=outcome.unidentifiable,
        correlation=outcome.correlation,
        experiments={e.name: {"kind": e.kind, "residual_before": outcome.residuals_before[e.name],
                              "residual_after": outcome.residuals_after[e.name],
                              "points": int(_points(e)), "fit_ok": goodness[e.name].ok,
                              "fit_ratio": goodness[e.name].ratio, "fit_limit": goodness[e.name].limit,
                              "worst_sensor": goodness[e.name].worst} for e in experiments},
        modes={"nominal": _modes(calibration.scenario), "fitted": _modes(scenario)},
        fit=outcome,
        curves=curves,
        fitted_data=data,
        goodness=goodness,
    )
    failed = [g for g in goodness.values() if not g.ok]
    if failed and not accept_misfit:
        raise MisfitError(misfit_message(failed), result)
    if failed:
        warnings.warn(misfit_message(failed, accepted=True), stacklevel=2)
    return result


def _restricted(calibration: Calibration, fit: Sequence[str]) -> Calibration:
    if isinstance(fit, str) or not all(isinstance(n, str) for n in fit) or not fit:
        raise ParameterError("fit: must be a non-empty list of the calibration's fitted names")
    for name in fit:
        if name not in calibration.names:
            raise ParameterError(f"fit: '{name}' is not fitted by this calibration "
                                 f"(fit: {', '.join(calibration.names)})")
    return replace(calibration, parameters=tuple(f for f in calibration.parameters if f.name in fit))


def _points(e: FloorExperiment | MoveExperiment) -> int:
    if isinstance(e, FloorExperiment):
        return 2 * e.H1.size
    return int(e.y.size)


def _fitted(calibration: Calibration, values: np.ndarray) -> tuple[dict, Scenario]:
    """The scenario file's keys with the fitted values, and the scenario they make."""
    _, data = scenario_data(calibration.scenario_file)
    layout = calibration.layout
    current = dict(zip(layout.names, calibration.vector(values).tolist(), strict=True))
    for f, v in zip(calibration.parameters, values, strict=True):
        for e in f.entries:
            set_parameter(data, layout.names[e], float(v), current)
    return data, scenario_from_dict(data, base_dir=calibration.scenario_file.parent,
                                    default_name=calibration.scenario_file.stem)


def _goodness(calibration: Calibration, experiments: list[FloorExperiment | MoveExperiment], outcome: Fit,
              curves: dict[str, Curves]) -> dict[str, Goodness]:
    """Each experiment's goodness of fit, its share of the parameters by its share of the residuals."""
    total = sum(outcome.residuals[e.name].size for e in experiments)
    files = {e.name: e.file.name for e in calibration.experiments}
    return {e.name: goodness_of_fit(e, files[e.name], outcome.residuals[e.name],
                                    len(calibration.parameters) * outcome.residuals[e.name].size / total,
                                    curves[e.name].fitted, curves[e.name].nominal)
            for e in experiments}


def _modes(scenario: Scenario) -> dict[str, list[float]]:
    m = modes(linearise(scenario))
    return {"frequencies_hz": [float(v) for v in m.frequencies_hz],
            "damping_ratios": [float(v) for v in m.damping_ratios]}


def _curves(e: FloorExperiment | MoveExperiment, p0: np.ndarray, p1: np.ndarray) -> Curves:
    outputs = tuple(s.name for s in e.table)
    units = tuple(s.unit for s in e.table)
    if isinstance(e, FloorExperiment):
        return Curves("floor", e.f, e.H1, e.predict(p0)[0], e.predict(p1)[0], e.coherence, outputs,
                      tuple(s.name for s in e.floor), units)
    return Curves("move", e.t, e.y, e.predict(p0), e.predict(p1), None, outputs, (), units)


check_public(globals())
