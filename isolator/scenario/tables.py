"""Numeric CSV files a scenario refers to: columns checked, floor spectra."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from isolator.errors import ScenarioError
from isolator.scenario.definitions import FloorSpectrum

__all__ = ["SPECTRUM_KINDS", "load_spectrum", "read_csv_columns", "spectrum_from_columns"]


def read_csv_columns(
    path: Path, key: str, required: tuple[str, ...], optional: tuple[str, ...] = (), exact: bool = False
) -> dict[str, np.ndarray]:
    """Numeric columns of a CSV file with a header line, checked.

    Parameters
    ----------
    path : Path
        The file.
    key : str
        Key path named in errors.
    required, optional : tuple of str
        Column names that must and may appear.
    exact : bool
        The header must be exactly ``required`` in that order.

    Raises
    ------
    ScenarioError
        Unreadable file, unknown or missing columns, a cell that is not a number.
    """
    try:
        with open(path, newline="") as handle:
            rows = list(csv.reader(handle))
    except OSError as exc:
        raise ScenarioError(f"{key}: cannot read '{path}' ({exc.strerror})") from None
    header = [h.strip() for h in rows[0]] if rows else []
    if exact and header != list(required):
        raise ScenarioError(f"{key}: '{path}' must be a CSV with the header '{','.join(required)}'")
    missing = [c for c in required if c not in header]
    unknown = [c for c in header if c not in required + optional]
    if missing or unknown or len(set(header)) != len(header):
        allowed = ", ".join(required + optional)
        raise ScenarioError(
            f"{key}: '{path}' must be a CSV whose header has {', '.join(required)} and maybe "
            f"other columns among ({allowed}), once each; got '{','.join(header)}'"
        )
    values = []
    for line, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        if len(row) != len(header):
            raise ScenarioError(f"{key}: '{path}' line {line}: needs {len(header)} values ({','.join(header)})")
        try:
            values.append([float(x) for x in row])
        except ValueError:
            raise ScenarioError(f"{key}: '{path}' line {line}: not all numbers") from None
    arr = np.array(values, dtype=float).reshape(-1, len(header))
    return {name: arr[:, i] for i, name in enumerate(header)}


SPECTRUM_KINDS = ("third-octave", "psd")


def load_spectrum(path: str | Path, kind: str, key: str = "spectrum") -> FloorSpectrum:
    """Read a floor vibration spectrum from a CSV file.

    Parameters
    ----------
    path : path
        CSV with a column ``frequency_hz`` and one or more of ``x, y, z``: RMS
        velocity per one-third-octave band [m/s] (``kind="third-octave"``, at the
        band centres) or velocity PSD [(m/s)^2/Hz] (``kind="psd"``).
    kind : {"third-octave", "psd"}
    key : str
        Key path named in errors.

    Raises
    ------
    ScenarioError
        A missing file, bad columns, non-increasing frequencies, negative values.
    """
    if kind not in SPECTRUM_KINDS:
        raise ScenarioError(f"{key}: kind must be one of {', '.join(SPECTRUM_KINDS)}, got '{kind}'")
    columns = read_csv_columns(Path(path), key, ("frequency_hz",), ("x", "y", "z"))
    columns["frequency"] = columns.pop("frequency_hz")
    return spectrum_from_columns(columns, kind, key)


def spectrum_from_columns(columns: dict[str, np.ndarray], kind: str, key: str) -> FloorSpectrum:
    f = columns.pop("frequency")
    if not columns:
        raise ScenarioError(f"{key}: needs values for at least one of x, y, z")
    if f.size < 2 or np.any(np.diff(f) <= 0) or f[0] <= 0:
        raise ScenarioError(f"{key}: frequencies must be > 0 and strictly increasing (at least two)")
    for axis, v in columns.items():
        if v.size != f.size:
            raise ScenarioError(f"{key}.{axis}: has {v.size} values for {f.size} frequencies")
        if not np.all(np.isfinite(v)) or np.any(v < 0):
            raise ScenarioError(f"{key}.{axis}: values must be finite and >= 0")
    return FloorSpectrum(kind=kind, frequency=f, values=columns)
