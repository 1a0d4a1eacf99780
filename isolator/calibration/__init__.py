"""Calibration of a scenario from measured records of a real table: records, spectra, the fit."""

from __future__ import annotations

__all__: list[str] = []
