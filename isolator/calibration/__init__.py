"""Calibration of a scenario from measured records of a real table (``docs/scenario-format.md``,
"Calibration from measured records"): the calibration file (``definition``), the records (``records``), the
multi-input H1 (``spectra``), the models' responses (``floor_model``, ``move_model``), the experiments'
residuals (``experiments``), the fit (``fit``), the result, its figure and report; :func:`calibrate` runs it."""

from __future__ import annotations

from isolator.calibration.calibrate import calibrate, read_records
from isolator.calibration.definition import (
    Calibration,
    Experiment,
    FitParameter,
    bundled_calibrations,
    load_calibration,
)
from isolator.calibration.records import Record, read_record
from isolator.calibration.result import CalibrationResult, ParameterEstimate
from isolator.calibration.spectra import FrfEstimate, h1_estimate

__all__ = [
    "Calibration",
    "CalibrationResult",
    "Experiment",
    "FitParameter",
    "FrfEstimate",
    "ParameterEstimate",
    "Record",
    "bundled_calibrations",
    "calibrate",
    "h1_estimate",
    "load_calibration",
    "read_record",
    "read_records",
]
