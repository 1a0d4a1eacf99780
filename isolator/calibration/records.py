"""Measured time records of a table: a CSV file or a UFF file (dataset 58), read and checked.

A record is the time axis and one signal per sensor it holds (see ``docs/scenario-format.md``,
"Calibration from measured records"). Every problem is one :class:`ScenarioError` whose message
starts with the file path as given and names the line, column or channel and the reason, e.g.
``floor.csv: line 7, column 'a-z': 'abc' is not a number``.
"""

from __future__ import annotations

import csv
import importlib
import io
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.files import check_input, read_text_table
from isolator.scenario.names import escaped, excerpt
from isolator.scenario.rules import closest

__all__ = ["DIRECTIONS", "UFF_SUFFIXES", "UNIFORM_TOLERANCE", "Record", "read_record"]

#: file suffixes (any case) read as universal files; any other suffix is read as CSV
UFF_SUFFIXES = (".uff", ".unv")
#: the most a sample spacing may differ from the mean spacing, relative to it
UNIFORM_TOLERANCE = 1e-6
#: a UFF channel's direction as given in ``uff`` -> pyuff's ``rsp_dir`` (1, 2, 3 = X, Y, Z; negative = minus)
DIRECTIONS = {"+X": 1, "X": 1, "-X": -1, "+Y": 2, "Y": 2, "-Y": -2, "+Z": 3, "Z": 3, "-Z": -3}
#: memory reading a UFF file takes per byte of it (pyuff holds its text and the values)
_UFF_FACTOR = 8.0
_AXES = {1: "X", 2: "Y", 3: "Z", 4: "RX", 5: "RY", 6: "RZ"}
#: what a CSV record is, as messages say it
_EXPECTED = "a CSV record: a header line t,<sensor>,... (the time [s], one column per sensor) and rows of numbers"


@dataclass(frozen=True)
class Record:
    """One measured record: uniformly sampled time and the sensors' signals (arrays read-only).

    Attributes
    ----------
    path : Path
        The file it came from.
    t : ndarray, shape (N,)
        Sample times [s], uniformly spaced, strictly increasing.
    channels : Mapping[str, ndarray]
        Sensor name -> (N,) samples in the sensor's SI quantity ([m], [m/s] or [m/s^2]), in file order.
    """

    path: Path
    t: np.ndarray
    channels: Mapping[str, np.ndarray]

    @property
    def rate(self) -> float:
        """Samples per second [Hz], from the mean spacing."""
        return float((self.t.size - 1) / (self.t[-1] - self.t[0]))


def read_record(
    path: str | Path, sensors: Sequence[str], uff: Mapping[str, tuple[int, str]] | None = None
) -> Record:
    """Read a measured record from a CSV or UFF file and check it.

    CSV (any suffix but ``.uff``/``.unv``): a header line with a column ``t`` [s] and one column per
    sensor, named exactly as the sensor; blank lines are skipped and a UTF-8 byte-order mark is
    accepted. UFF (``.uff``/``.unv``, any case; needs ``pyuff``): the datasets 58 of function type 1
    (time response) whose response node and direction are a sensor's in ``uff``; other datasets
    are skipped. The values are taken as they are, in the sensor's SI quantity: the units a UFF
    file declares are not read or converted.

    Parameters
    ----------
    path : str or Path
        The file; named as given at the start of every error.
    sensors : sequence of str
        The sensor names a column or channel may have; a record need not hold them all.
    uff : mapping of str to (int, str), optional
        For UFF files: sensor name -> (response node, direction), the direction one of ``+X, -X,
        +Y, -Y, +Z, -Z`` (``X`` is ``+X``). A dataset is a sensor's when its ``rsp_node`` and
        ``rsp_dir`` are exactly these (a ``-Z`` sensor takes the dataset written with direction -3,
        not the +3 one). Not used for CSV files.

    Returns
    -------
    Record
        Its channels in file order (CSV columns; UFF datasets).

    Raises
    ------
    ScenarioError
        A missing, empty, non-UTF-8 or unparseable file, bad columns or channels, a cell that is
        not a finite number, rows of the wrong length, fewer than two samples, time not strictly
        increasing or not uniformly sampled (to :data:`UNIFORM_TOLERANCE` of the mean spacing).
    ParameterError
        A sensor named ``t``, or a ``uff`` entry that names no sensor or has a bad node or direction.
    """
    if "t" in sensors:
        raise ParameterError("sensors: 't' is the time column of a record, not a sensor name")
    file = Path(path)
    where = escaped(path, 120)
    if not file.exists():
        raise ScenarioError(f"{where}: no such file")
    if file.is_dir():
        raise ScenarioError(f"{where}: is a folder, not a record file")
    if file.suffix.lower() in UFF_SUFFIXES:
        t, channels = _read_uff(file, where, _uff_channels(sensors, uff))
    else:
        t, channels = _read_csv(file, where, sensors)
    t.flags.writeable = False
    for values in channels.values():
        values.flags.writeable = False
    return Record(path=file, t=t, channels=MappingProxyType(channels))


def _read_csv(file: Path, where: str, sensors: Sequence[str]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The time and the sensor columns of a CSV record.

    A plain file (one row a line, no quotes, no blank lines after the header) is parsed by
    ``numpy.loadtxt``; anything else, and any file that fails a check, is read again row by row
    with :mod:`csv` so that the error names its line and column.
    """
    text = read_text_table(file, "", _EXPECTED)
    lines = text.splitlines()
    head = next((i for i, line in enumerate(lines) if line.strip()), None)
    if head is None:
        raise ScenarioError(f"{where}: is empty (needs a header line t,<sensor>,... and data rows)")
    if '"' not in text and "" not in lines[head + 1 :] and len(lines) - head > 2:
        header = [cell.strip() for cell in next(csv.reader([lines[head]]))]
        _check_header(f"{where}: line {head + 1}", header, sensors)
        try:
            values = np.loadtxt(lines[head + 1 :], delimiter=",", comments=None, ndmin=2, dtype=float)
        except ValueError:
            values = None
        if values is not None and values.shape[1] == len(header) and np.isfinite(values).all():
            return _columns(header, values, lambda i: f"{where}: line {head + 2 + i}")
    header, rows, values = _csv_rows(where, text, sensors)
    return _columns(header, values, lambda i: f"{where}: line {rows[i][0]}")


def _csv_rows(
    where: str, text: str, sensors: Sequence[str]
) -> tuple[list[str], list[tuple[int, list[str]]], np.ndarray]:
    """The header, the data rows (line, cells) and their values, read row by row and checked."""
    try:
        reader = csv.reader(io.StringIO(text, newline=""))
        rows = [(reader.line_num, row) for row in reader if "".join(row).strip()]
    except csv.Error as exc:
        raise ScenarioError(f"{where}: not a CSV file ({excerpt(exc)})") from None
    head_line, header = rows[0][0], [cell.strip() for cell in rows[0][1]]
    _check_header(f"{where}: line {head_line}", header, sensors)
    data = rows[1:]
    if len(data) < 2:
        got = "no data rows" if not data else "one data row"
        raise ScenarioError(f"{where}: has {got} (a record needs at least two samples)")
    width = len(header)
    for line, row in data:
        if len(row) != width:
            raise ScenarioError(f"{where}: line {line}: {len(row)} values for {width} columns "
                                f"({','.join(header)})")
    try:
        values = np.array([row for _, row in data], dtype=float)
    except ValueError:
        values = _first_bad_cell(where, data, header)
    finite = np.isfinite(values)
    if not finite.all():
        i, j = np.argwhere(~finite)[0]
        raise ScenarioError(f"{where}: line {data[i][0]}, column '{excerpt(header[j])}': "
                            f"{excerpt(data[i][1][j].strip())} (samples must be finite numbers)")
    return header, data, values


def _columns(
    header: list[str], values: np.ndarray, at: Callable[[int], str]
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The time (checked; ``at(i)`` names data row ``i``) and the sensor columns of a table."""
    t = values[:, header.index("t")].copy()
    _check_time(t, at)
    return t, {name: values[:, j].copy() for j, name in enumerate(header) if name != "t"}


def _check_header(where: str, header: list[str], sensors: Sequence[str]) -> None:
    """Refuse a header without ``t``, with a column naming no sensor, repeated or without a sensor column.

    Until the header has its ``t`` column the file is not known to be a record: nothing of it is quoted (it
    may be any file, a secret's first line)."""
    if "t" not in header:
        raise ScenarioError(f"{where}: no column 't' (the time [s]); expected {_EXPECTED}")
    for j, name in enumerate(header):
        if not name:
            raise ScenarioError(f"{where}: column {j + 1} has no name (the header: t and one sensor per column)")
        if header.count(name) > 1:
            raise ScenarioError(f"{where}: column '{excerpt(name)}' appears {header.count(name)} times")
        if name != "t" and name not in sensors:
            near = closest(name, list(sensors))
            hint = f"; did you mean '{near}'?" if near else ""
            known = ", ".join(sensors) if sensors else "none"
            raise ScenarioError(f"{where}: column '{excerpt(name)}' names no sensor (the sensors: {known}){hint}")
    if len(header) == 1:
        raise ScenarioError(f"{where}: only the column 't'; a record needs at least one sensor column")


def _first_bad_cell(where: str, data: list[tuple[int, list[str]]], header: list[str]) -> np.ndarray:
    """Find and report the first cell that is not a number (numpy refused the whole table)."""
    for line, row in data:
        for name, cell in zip(header, row, strict=True):
            try:
                float(cell)
            except ValueError:
                raise ScenarioError(f"{where}: line {line}, column '{excerpt(name)}': '{excerpt(cell.strip())}' is "
                                    "not a number") from None
    raise ScenarioError(f"{where}: a cell is not a number")  # numpy and float() disagree: still one line


def _check_time(t: np.ndarray, at: Callable[[int], str]) -> None:
    """Refuse a time axis that is not strictly increasing or not uniform; ``at(i)`` names sample ``i``."""
    step = np.diff(t)
    if np.any(step <= 0):
        i = int(np.argmax(step <= 0)) + 1
        raise ScenarioError(f"{at(i)}: t = {t[i]:.9g} is not after t = {t[i - 1]:.9g} (t must increase "
                            "strictly)")
    mean = (t[-1] - t[0]) / (t.size - 1)
    off = np.abs(step - mean) > UNIFORM_TOLERANCE * mean
    if off.any():
        # named: where the spacing first changes (the mean is shifted by a jump, so every step is "off")
        jump = np.abs(step - step[0]) > UNIFORM_TOLERANCE * mean
        i = int(np.argmax(jump if jump.any() else off)) + 1
        raise ScenarioError(f"{at(i)}: t = {t[i]:.9g} is {step[i - 1]:.9g} s after the previous sample; the "
                            f"mean spacing is {mean:.9g} s (a record must be uniformly sampled, each spacing "
                            f"within {UNIFORM_TOLERANCE:g} of the mean)")


def _uff_channels(sensors: Sequence[str], uff: Mapping[str, tuple[int, str]] | None) -> dict[tuple[int, int], str]:
    """The ``uff`` mapping checked and turned around: (node, rsp_dir) -> sensor name."""
    channels: dict[tuple[int, int], str] = {}
    for name, entry in (uff or {}).items():
        key = f"uff['{name}']"
        if name not in sensors:
            raise ParameterError(f"{key}: names no sensor; the sensors: {', '.join(sensors) or 'none'}")
        if not (isinstance(entry, tuple | list) and len(entry) == 2):
            raise ParameterError(f"{key}: must be (node, direction), got {entry!r}")
        node, direction = entry
        if not isinstance(node, int | np.integer) or isinstance(node, bool):
            raise ParameterError(f"{key}: the node must be an integer, got {node!r}")
        if not isinstance(direction, str) or direction.strip().upper() not in DIRECTIONS:
            raise ParameterError(f"{key}: the direction must be one of +X, -X, +Y, -Y, +Z, -Z, got {direction!r}")
        channel = (int(node), DIRECTIONS[direction.strip().upper()])
        if channel in channels:
            raise ParameterError(f"{key}: node {channel[0]} {_dir(channel[1])} is also sensor "
                                 f"'{channels[channel]}'s")
        channels[channel] = name
    return channels


def _dir(rsp_dir: int) -> str:
    """A pyuff ``rsp_dir`` as text: ``+Z``, ``-X``, ``+RY`` (0 or unknown: as a number)."""
    axis = _AXES.get(abs(rsp_dir))
    return f"{'-' if rsp_dir < 0 else '+'}{axis}" if axis else f"direction {rsp_dir}"


def _read_uff(
    file: Path, where: str, wanted: dict[tuple[int, int], str]
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The time and the sensor channels of a UFF record (datasets 58, function type 1)."""
    try:
        pyuff: Any = importlib.import_module("pyuff")
    except ImportError:
        raise ScenarioError(f"{where}: reading UFF needs pyuff: pip install 'isolator[uff]'") from None
    try:
        if not check_input(file, "", factor=_UFF_FACTOR):  # a regular file, checked before pyuff opens it
            raise ScenarioError(f"{where}: is empty (a UFF record needs datasets 58)")
        handle = pyuff.UFF(str(file))
        indices = [i for i, kind in enumerate(handle.get_set_types()) if int(kind) == 58]
        sets = handle.read_sets(indices) if indices else []
    except ScenarioError:
        raise
    except Exception as exc:  # pyuff raises bare Exceptions on malformed files, their text quoting the file's
        raise ScenarioError(f"{where}: cannot be read as a universal file ({type(exc).__name__}; expected UFF "
                            "datasets 58 of the sensors' signals)") from None
    sets = [sets] if isinstance(sets, dict) else list(sets)
    found: dict[str, tuple[np.ndarray, int, float, float, str]] = {}
    held: list[str] = []
    for dataset in sets:
        channel = (int(dataset["rsp_node"]), int(dataset["rsp_dir"]))
        label = f"node {channel[0]} {_dir(channel[1])}"
        held.append(label)
        name = wanted.get(channel)
        if name is None:
            continue
        if int(dataset["func_type"]) != 1:
            raise ScenarioError(f"{where}: channel {label} (sensor '{name}') has function type "
                                f"{int(dataset['func_type'])}, not 1 (time response)")
        if name in found:
            raise ScenarioError(f"{where}: channel {label} (sensor '{name}') appears in two datasets 58")
        found[name] = (*_uff_samples(where, label, dataset), label)
    if not found:
        holds = ", ".join(dict.fromkeys(held)) or "no datasets 58"
        asked = ", ".join(f"'{n}' = node {c[0]} {_dir(c[1])}" for c, n in wanted.items()) or "no uff mapping given"
        raise ScenarioError(f"{where}: no channel of a sensor ({asked}); the file holds: {holds}")
    first = next(iter(found))
    _, n0, start0, step0, label0 = found[first]
    for _values, n, start, step, label in found.values():
        if (n, start, step) != (n0, start0, step0):
            raise ScenarioError(f"{where}: channels {label0} and {label} have different time axes (start "
                                f"{start0:g} s, spacing {step0:g} s, {n0} samples vs {start:g} s, {step:g} s, "
                                f"{n} samples)")
    t = start0 + step0 * np.arange(n0)
    return t, {name: entry[0] for name, entry in found.items()}


def _uff_samples(where: str, label: str, dataset: Mapping[str, Any]) -> tuple[np.ndarray, int, float, float]:
    """One dataset 58's samples and time axis (count, start, spacing), checked."""
    values = np.asarray(dataset["data"])
    if np.iscomplexobj(values):
        raise ScenarioError(f"{where}: channel {label} holds complex values (a time record must be real)")
    values = values.astype(float)
    n = int(dataset.get("num_pts", values.size))
    if n != values.size:
        raise ScenarioError(f"{where}: channel {label} declares {n} points and holds {values.size}")
    if n < 2:
        raise ScenarioError(f"{where}: channel {label} has {n} sample{'s' if n != 1 else ''} (a record needs "
                            "at least two)")
    bad = ~np.isfinite(values)
    if bad.any():
        i = int(np.argmax(bad))
        raise ScenarioError(f"{where}: channel {label}, sample {i}: {values[i]} (samples must be finite numbers)")
    if int(dataset.get("abscissa_spacing", 1)) == 1:
        start, step = float(dataset["abscissa_min"]), float(dataset["abscissa_inc"])
        if not (np.isfinite(start) and np.isfinite(step) and step > 0):
            raise ScenarioError(f"{where}: channel {label}: abscissa start {start:g} s, increment {step:g} s "
                                "(the increment must be > 0)")
    else:  # uneven abscissa: accepted when its values are uniform all the same
        x = np.asarray(dataset["x"], dtype=float)
        _check_time(x, lambda i: f"{where}: channel {label}, sample {i}")
        start, step = float(x[0]), float((x[-1] - x[0]) / (n - 1))
    return values, n, start, step
