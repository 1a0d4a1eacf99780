"""Numeric CSV files a scenario refers to: columns checked, floor spectra."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from isolator.errors import ScenarioError
from isolator.scenario.arguments import check_public
from isolator.scenario.files import read_text_table
from isolator.scenario.ground import FloorSpectrum
from isolator.scenario.keys import KeyReader
from isolator.scenario.names import escaped, excerpt

__all__ = ["LINE", "MAX_FLOOR_VELOCITY", "SPECTRUM_KINDS", "check_floor_level", "load_spectrum", "read_csv_columns",
           "read_samples", "spectrum_from_columns"]

#: the entry of :func:`read_csv_columns`'s result that holds each data row's line number (``lines=True``)
LINE = "#line"


def read_csv_columns(
    path: Path,
    key: str,
    required: tuple[str, ...],
    optional: tuple[str, ...] = (),
    exact: bool = False,
    *,
    min_rows: int = 2,
    increasing: str | None = None,
    repeats: bool = False,
    blank: tuple[str, ...] = (),
    lines: bool = False,
) -> dict[str, np.ndarray]:
    """Numeric columns of a CSV file with a header line, checked.

    Every problem is one :class:`ScenarioError` naming ``key``, the file, the line (and column) and
    the reason. A UTF-8 byte-order mark (as spreadsheets write) is accepted; blank lines are skipped.

    Parameters
    ----------
    path : Path
        The file.
    key : str
        Key path (or option) named in errors.
    required, optional : tuple of str
        Column names that must and may appear.
    exact : bool
        The header must be exactly ``required`` in that order.
    min_rows : int
        Fewest data rows.
    increasing : str, optional
        A column whose values must increase strictly down the file (``repeats``: a value may
        appear twice in a row, for a step).
    blank : tuple of str
        Columns whose cells may be empty (read as NaN).
    lines : bool
        Add the entry :data:`LINE`: each data row's line number in the file.

    Raises
    ------
    ScenarioError
        An unreadable, empty or non-UTF-8 file; unknown, missing or repeated columns; a row of the
        wrong length; a cell that is not a finite number; too few rows; values not increasing.
    """
    where = f"{key}: '{escaped(path, 120)}'"
    text = read_text_table(path, key, f"a CSV table with the header {','.join(required)},... and rows of numbers")
    try:
        reader = csv.reader(io.StringIO(text, newline=""))
        rows = [(reader.line_num, row) for row in reader if any(cell.strip() for cell in row)]
    except csv.Error as exc:
        raise ScenarioError(f"{where}: not a CSV file ({escaped(exc, 80)})") from None
    if not rows:
        raise ScenarioError(f"{where}: is empty (needs a header line {','.join(required)},... and data rows)")
    head_line, header = rows[0][0], [h.strip() for h in rows[0][1]]
    columns = _check_header(f"{where} line {head_line}", header, required, optional, exact)
    values = np.empty((len(rows) - 1, len(header)))
    for i, (line, row) in enumerate(rows[1:]):
        if len(row) != len(header):
            raise ScenarioError(f"{where} line {line}: {len(row)} values for {len(header)} columns ({columns})")
        if not blank:  # a row of finite numbers at once; a bad cell is named by the loop below
            try:
                numbers = [float(cell) for cell in row]
            except ValueError:
                numbers = []
            if numbers and all(math.isfinite(v) for v in numbers):
                values[i] = numbers
                continue
        for j, cell in enumerate(row):
            if header[j] in blank and not cell.strip():
                values[i, j] = np.nan
                continue
            try:
                values[i, j] = float(cell)
            except ValueError:
                raise ScenarioError(f"{where} line {line}, column '{excerpt(header[j])}': '{excerpt(cell.strip())}' "
                                    "is not a number") from None
            if not np.isfinite(values[i, j]):
                raise ScenarioError(f"{where} line {line}, column '{excerpt(header[j])}': "
                                    f"{excerpt(cell.strip())} is not a finite number")
    n = values.shape[0]
    if n < min_rows:
        got = "no data rows" if n == 0 else f"{n} data row{'s' if n > 1 else ''}"
        raise ScenarioError(f"{where}: has {got} (needs at least {min_rows})")
    if increasing is not None:
        _check_increasing(where, [line for line, _ in rows[1:]], values[:, header.index(increasing)],
                          increasing, repeats)
    out = {name: values[:, i] for i, name in enumerate(header)}
    if lines:
        out[LINE] = np.array([line for line, _ in rows[1:]], dtype=int)
    return out


def _check_header(
    where: str, header: list[str], required: tuple[str, ...], optional: tuple[str, ...], exact: bool
) -> str:
    """The header as text, after checking its columns; nothing of it is quoted before the required columns
    show the file is such a table (it may be any file, a secret's first line)."""
    got = excerpt(",".join(header))
    if exact and header != list(required):
        order = ", its columns in another order" if sorted(header) == sorted(required) else ""
        raise ScenarioError(f"{where}: the header must be '{','.join(required)}' (this file's first line is "
                            f"another{order})")
    for name in required:
        if name not in header:
            raise ScenarioError(f"{where}: column '{name}' missing (expected a header with "
                                f"{', '.join(required)} and rows of numbers)")
    allowed = required + optional
    for name in header:
        if name not in allowed:
            raise ScenarioError(f"{where}: column '{excerpt(name)}' is not one of {', '.join(allowed)}")
        if header.count(name) > 1:
            raise ScenarioError(f"{where}: column '{excerpt(name)}' appears {header.count(name)} times")
    return got


def _check_increasing(where: str, lines: list[int], v: np.ndarray, name: str, repeats: bool) -> None:
    for i in range(1, v.size):
        if v[i] < v[i - 1] or (v[i] == v[i - 1] and not repeats):
            raise ScenarioError(f"{where} line {lines[i]}: {name} = {v[i]:g} is not after {v[i - 1]:g} on line "
                                f"{lines[i - 1]} ({name} must increase)")
        if v[i] == v[i - 1] and i >= 2 and v[i - 1] == v[i - 2]:
            raise ScenarioError(f"{where} line {lines[i]}: {name} = {v[i]:g} for the third time (it may repeat "
                                "once, for a step)")


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

    Returns
    -------
    FloorSpectrum
        The frequencies [Hz] and each axis' values, of the ``kind`` given.

    Raises
    ------
    ScenarioError
        A missing file, bad columns, non-increasing frequencies, negative values.
    """
    if kind not in SPECTRUM_KINDS:
        raise ScenarioError(f"{key}: kind must be one of {', '.join(SPECTRUM_KINDS)}, got '{kind}'")
    columns = read_csv_columns(Path(path), key, ("frequency_hz",), ("x", "y", "z"), increasing="frequency_hz")
    columns["frequency"] = columns.pop("frequency_hz")
    return spectrum_from_columns(columns, kind, key, source=str(path))


def spectrum_from_columns(
    columns: dict[str, np.ndarray], kind: str, key: str, source: str | None = None
) -> FloorSpectrum:
    """A floor spectrum from its columns (``frequency`` and some of ``x, y, z``), checked.

    The frequencies of a third-octave spectrum must be band centres (``10^(n/10)`` Hz, or their
    nominal values 1.25, 1.6, ...); a PSD whose frequencies are three or more consecutive band centres
    is taken for a third-octave spectrum given the wrong kind. ``source`` (a file) is named after ``key``.
    """
    where = key if source is None else f"{key}: '{source}'"
    f = columns.pop("frequency")
    if not columns:
        raise ScenarioError(f"{where}: needs values for at least one of x, y, z")
    if f.size < 2 or np.any(np.diff(f) <= 0) or f[0] <= 0:
        raise ScenarioError(f"{where}: frequencies must be > 0 and strictly increasing (at least two)")
    for axis, v in columns.items():
        name = f"{key}.{axis}" if source is None else f"{where}, column '{axis}'"
        if v.size != f.size:
            raise ScenarioError(f"{name}: has {v.size} values for {f.size} frequencies")
        if not np.all(np.isfinite(v)) or np.any(v < 0):
            raise ScenarioError(f"{name}: values must be finite and >= 0")
    _check_kind(f, kind, where)
    spectrum = FloorSpectrum(kind=kind, frequency=f, values=columns)
    check_floor_level(spectrum, where)
    return spectrum


#: the largest RMS velocity [m/s] a floor may have in a one-third-octave band: above any floor a machine is set up
#: on (VC-A is 50 um/s, ISO's workshop curve 800 um/s); a floor in um/s typed as m/s is a million times too large
MAX_FLOOR_VELOCITY = 1e-3
#: the units a floor spectrum's numbers were likely typed in, by their factor on m/s
_VELOCITY_UNITS = ((1e3, "mm/s"), (1e6, "um/s"), (1e9, "nm/s"))


def check_floor_level(spectrum: FloorSpectrum, where: str) -> None:
    """Refuse a floor spectrum whose RMS velocity in a one-third-octave band exceeds :data:`MAX_FLOOR_VELOCITY`
    on any axis: one :class:`ScenarioError` starting with ``where``, naming the largest band, its axis and the
    unit the numbers were likely typed in (the least factor that brings the band below the limit)."""
    centres, rms = spectrum.band_rms()
    worst = max(((float(np.nan_to_num(v, nan=np.inf).max(initial=0.0)), a) for a, v in rms.items()), default=(0.0, ""))
    value, axis = worst
    if value <= MAX_FLOOR_VELOCITY:
        return
    band = float(centres[int(np.argmax(np.nan_to_num(rms[axis], nan=np.inf)))])
    likely = next((u for factor, u in _VELOCITY_UNITS if value / factor <= MAX_FLOOR_VELOCITY), None)
    per_hz = spectrum.kind == "psd"
    unit = (f"; the numbers look like ({likely})^2/Hz given as (m/s)^2/Hz" if per_hz else
            f"; the numbers look like {likely} given as m/s") if likely else ""
    raise ScenarioError(f"{where}: the floor's RMS velocity in the one-third-octave band at {band:.3g} Hz is "
                        f"{value:.3g} m/s on {axis}, above {MAX_FLOOR_VELOCITY * 1e3:g} mm/s (more than any floor a "
                        f"machine stands on: VC-A is 50 um/s){unit}")


def _check_kind(f: np.ndarray, kind: str, where: str) -> None:
    """Refuse a spectrum whose frequencies belong to the other kind."""
    band = 10 * np.log10(f)  # base-10 one-third-octave band numbers: integers at the centres
    centre = np.abs(band - np.round(band)) < 0.1  # within 2.3 %: the nominal centres 1.25, 1.6, 3.15, ...
    if kind == "third-octave" and not centre.all():
        off = float(f[np.argmin(centre)])
        raise ScenarioError(f"{where}: {off:.4g} Hz is not a one-third-octave band centre (1, 1.25, 1.6, 2, 2.5, "
                            "3.15, ... Hz); a spectrum on another frequency grid is a velocity PSD: give its "
                            "kind as psd")
    if kind == "psd" and f.size >= 3 and centre.all() and np.all(np.diff(np.round(band)) == 1):
        raise ScenarioError(f"{where}: the frequencies are consecutive one-third-octave band centres "
                            f"({f[0]:.4g} to {f[-1]:.4g} Hz), as in a third-octave spectrum (band RMS "
                            "velocities), not a PSD's frequency grid: give its kind as third-octave")


def read_samples(r: KeyReader, base_dir: Path) -> tuple[np.ndarray, np.ndarray]:
    """A sampled profile's ``t`` and ``q`` [s, m]: from ``file`` (a CSV with those columns) or inline."""
    if r.has("file"):
        if r.has("t") or r.has("q"):
            raise ScenarioError(f"{r.key('file')}: give either file or inline t and q, not both")
        file_key = r.key("file")
        columns = read_csv_columns(base_dir / r.string("file"), file_key, ("t", "q"), exact=True, increasing="t")
        t, q, key = columns["t"], columns["q"], file_key
    else:
        tk, qk = r.key("t"), r.key("q")
        t_raw, q_raw = r.raw("t"), r.raw("q")
        for k, v in ((tk, t_raw), (qk, q_raw)):
            if not isinstance(v, list) or not all(
                isinstance(x, int | float) and not isinstance(x, bool) for x in v
            ):
                raise ScenarioError(f"{k}: must be a list of numbers")
        t, q, key = np.array(t_raw, float), np.array(q_raw, float), tk
        if len(t) != len(q):
            raise ScenarioError(f"{qk}: has {len(q)} values but t has {len(t)}")
    r.used.update({"file", "t", "q"})
    if len(t) < 2:
        raise ScenarioError(f"{key}: needs at least two samples")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q))):
        raise ScenarioError(f"{key}: samples must be finite (found NaN or infinity)")
    if np.any(np.diff(t) <= 0):
        raise ScenarioError(f"{key}: sample times must be strictly increasing")
    if t[0] < 0:
        raise ScenarioError(f"{key}: sample times must be >= 0, got {t[0]:g}")
    return t, q


check_public(globals(), ("load_spectrum"))
