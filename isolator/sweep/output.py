"""A sweep's rows written as they arrive: CSV, or Parquet when the path ends in ``.parquet`` (rows go to a
CSV beside it, ``<out>.partial.csv``, turned into Parquet when the sweep ends, so that an interrupted
sweep leaves a readable file either way); read back, column by column; resumed from what is on disk, the
sweep that wrote it named in a sidecar ``<out>.sweep.json`` (:func:`check_sidecar`)."""

from __future__ import annotations

import csv
import json
import math
import os
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.definitions import SIGNALS

__all__ = ["SUFFIXES", "TEXT_COLUMNS", "RowSink", "check_format", "check_sidecar", "column_names", "done_designs",
           "read_columns", "sidecar_path", "staging_path", "write_sidecar"]

#: the output formats, by extension
SUFFIXES = (".csv", ".parquet")
#: the columns that hold words (the others numbers)
TEXT_COLUMNS = ("status", "reason")


def column_names(names: Sequence[str], frequencies: Sequence[float], axes: Sequence[str], modes: int,
                 metrics: Sequence[str] = (), budget: Sequence[str] = ()) -> list[str]:
    """The output's columns: the swept names as given, ``settling_time_max``, ``settling:<signal>``,
    ``peak:<signal>``, ``status``, then ``reason``, ``design`` (the design's index), ``band:<signal>`` (the
    settling band's half-widths [m or rad]), ``metrics`` (:func:`isolator.sweep.metrics.metric_columns`),
    ``transmissibility:<axis>@<f>Hz``, ``mode:<k>`` [Hz] and the ``budget`` columns
    (:func:`isolator.sweep.budget.budget_columns`)."""
    out = [*names, "settling_time_max", *[f"settling:{s}" for s in SIGNALS], *[f"peak:{s}" for s in SIGNALS]]
    out += ["status", "reason", "design", *[f"band:{s}" for s in SIGNALS], *metrics]
    out += [f"transmissibility:{a}@{f:g}Hz" for f in frequencies for a in axes]
    return out + [f"mode:{k + 1}" for k in range(modes)] + list(budget)


def staging_path(path: Path) -> Path:
    """Where the rows of ``path`` are appended while the sweep runs (``path`` itself for CSV)."""
    return path.with_name(path.name + ".partial.csv") if path.suffix.lower() == ".parquet" else path


def _text(value: object) -> str:
    return repr(float(value)) if isinstance(value, float | np.floating) else str(value)


class RowSink:
    """Appends rows to the staging CSV, flushed after every chunk.

    Parameters
    ----------
    path : Path
        The output (``.csv`` or ``.parquet``).
    columns : sequence of str
    append : bool
        Continue a file whose rows are on disk (its header checked by :func:`done_designs`).
    """

    def __init__(self, path: Path, columns: Sequence[str], append: bool) -> None:
        self.path = path
        self.columns = list(columns)
        staging = staging_path(path)
        fresh = not (append and staging.exists())
        self._file = staging.open("w" if fresh else "a", newline="", encoding="utf-8")
        self._writer = csv.writer(self._file)
        if fresh:
            self._writer.writerow(self.columns)
            self._file.flush()

    def write(self, rows: Sequence[Sequence[object]]) -> None:
        """Append rows (one value per column) and flush them to the file."""
        self._writer.writerows([[_text(v) for v in row] for row in rows])
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self, complete: bool) -> None:
        """Close; a complete ``.parquet`` sweep is then converted and its staging CSV removed."""
        self._file.close()
        if complete and self.path.suffix.lower() == ".parquet":
            _to_parquet(staging_path(self.path), self.path)


def check_format(path: Path) -> None:
    """``.csv``, or ``.parquet`` with pyarrow installed; else one clear :class:`ParameterError`."""
    if path.suffix.lower() not in SUFFIXES:
        raise ParameterError(f"out: '{path}' has extension '{path.suffix}'; supported: {', '.join(SUFFIXES)}")
    if path.suffix.lower() == ".parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise ParameterError("out: writing .parquet needs pyarrow: pip install pyarrow (or write .csv)") from None


def _to_parquet(source: Path, path: Path) -> None:
    """The staging CSV as Parquet, a block at a time (memory flat), written beside and moved into place."""
    from pyarrow import csv as pacsv
    from pyarrow import parquet, string

    types = {c: string() for c in TEXT_COLUMNS}
    reader = pacsv.open_csv(source, convert_options=pacsv.ConvertOptions(column_types=types,
                                                                         strings_can_be_null=False))
    temporary = path.with_name(path.name + ".tmp")
    with parquet.ParquetWriter(temporary, reader.schema) as writer:
        for batch in reader:
            writer.write_batch(batch)
    os.replace(temporary, path)
    source.unlink()


def _rows(path: Path) -> Iterator[list[str]]:
    """The rows of a CSV, the header first."""
    with path.open(newline="", encoding="utf-8") as f:
        yield from csv.reader(f)


def read_columns(path: Path, wanted: Sequence[str] | None = None) -> dict[str, np.ndarray]:
    """Columns of a sweep's output (all by default): numbers as float arrays, ``status`` and ``reason``
    as object arrays of str."""
    if path.suffix.lower() == ".parquet" and path.exists():
        from pyarrow import parquet

        table = parquet.read_table(path, columns=None if wanted is None else list(wanted))
        return {name: _typed(name, table.column(name).to_pylist()) for name in table.column_names}
    rows = _rows(staging_path(path))
    header = next(rows)
    keep = [(j, name) for j, name in enumerate(header) if wanted is None or name in wanted]
    values: dict[str, list[str]] = {name: [] for _, name in keep}
    for row in rows:
        for j, name in keep:
            values[name].append(row[j])
    return {name: _typed(name, v) for name, v in values.items()}


def _typed(name: str, values: Sequence[object]) -> np.ndarray:
    if name in TEXT_COLUMNS:
        return np.array([str(v) for v in values], dtype=object)
    return np.array([math.nan if v in ("", None) else float(v) for v in values], dtype=float)  # type: ignore[arg-type]


def done_designs(path: Path, columns: Sequence[str], names: Sequence[str], values: np.ndarray) -> np.ndarray:
    """Which designs (by index) the file at ``path`` holds already, for ``resume``: its columns must be the
    sweep's and each row's swept values its design's; a last row cut short by an interrupt is removed.

    Raises
    ------
    ParameterError
        The file holds another sweep's rows (other columns, or other values for a design).
    """
    staging = staging_path(path)
    done = np.zeros(values.shape[0], dtype=bool)
    if not staging.exists():
        if path.exists():  # a finished .parquet
            from pyarrow import parquet

            _check_header(path, parquet.read_schema(path).names, columns)
            table = read_columns(path, ["design", *names])
            got = np.column_stack([table[n] for n in names]) if names else np.zeros((table["design"].size, 0))
            for i, row in zip(table["design"], got, strict=True):
                _check_row(path, i, row, values)
                done[int(i)] = True
        return done
    raw = staging.read_bytes()
    if raw and not raw.endswith(b"\n"):  # the last row was cut short
        with staging.open("r+b") as f:
            f.truncate(raw.rfind(b"\n") + 1)
    rows = _rows(staging)
    header = next(rows, None)
    if header is None:
        staging.unlink()
        return done
    _check_header(path, header, columns)
    at = header.index("design")
    for row in rows:
        i = float(row[at])
        _check_row(path, i, np.array([float(v) for v in row[: len(names)]]), values)
        done[int(i)] = True
    return done


def _check_row(path: Path, design: float, got: np.ndarray, values: np.ndarray) -> None:
    """A row's design index is one of this sweep's and its swept values are that design's."""
    if not (design.is_integer() and 0 <= design < values.shape[0]):
        raise ParameterError(f"out: '{path}' holds another sweep's rows (design {design:g} is not one of this "
                             f"sweep's {values.shape[0]}); force=True starts again")
    if not np.array_equal(got, values[int(design)]):
        raise ParameterError(f"out: '{path}' holds another sweep's rows (design {int(design)} differs); "
                             "force=True starts again")


def _check_header(path: Path, header: Sequence[str], columns: Sequence[str]) -> None:
    if list(header) != list(columns):
        raise ParameterError(f"out: '{path}' holds other columns than this sweep's ({', '.join(header[:4])}, ...); "
                             "force=True starts again")


def sidecar_path(path: Path) -> Path:
    """Where the sweep that writes ``path`` is described: ``<out>.sweep.json``."""
    return path.with_name(path.name + ".sweep.json")


def _plain(identity: Mapping[str, Any]) -> dict[str, Any]:
    """As JSON gives it back (tuples as lists)."""
    return dict(json.loads(json.dumps(dict(identity))))


def write_sidecar(path: Path, identity: Mapping[str, Any]) -> None:
    """Describe the sweep that writes ``path`` (JSON beside it), replacing any description there."""
    sidecar = sidecar_path(path)
    temporary = sidecar.with_name(sidecar.name + ".tmp")
    temporary.write_text(json.dumps(_plain(identity), indent=1) + "\n", encoding="utf-8")
    os.replace(temporary, sidecar)


def check_sidecar(path: Path, identity: Mapping[str, Any]) -> None:
    """For ``resume``: the sweep described beside ``path`` must be this one (a file without a description,
    written before there were any, is taken as it is).

    Raises
    ------
    ParameterError
        One line naming what differs (the scenario, the model, the band, the sampling, the extras).
    """
    sidecar = sidecar_path(path)
    if not sidecar.exists():
        return
    try:
        stored = json.loads(sidecar.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ParameterError(f"out: cannot read '{sidecar}' ({exc}); force=True starts again") from None
    wanted = _plain(identity)
    differ = [k for k in wanted if not isinstance(stored, dict) or stored.get(k) != wanted[k]]
    if differ:
        if "model" in differ and "scenario_key" in differ:  # the hash is of the scenario and the model
            differ.remove("scenario_key")
        shown = ", ".join("the scenario" if k == "scenario_key" else k for k in differ)
        raise ParameterError(f"out: '{path}' was written by another sweep (it differs in: {shown}; see "
                             f"'{sidecar.name}'); force=True starts again")


def prepared(path: Path | None, resume: bool, force: bool, identity: Mapping[str, Any], columns: list[str],
             names: Sequence[str], values: np.ndarray, best_by: str, count: int
             ) -> tuple[np.ndarray, dict[str, np.ndarray] | None]:
    """The designs an ``out`` file already holds (``resume``) and its ``best_by``, ``status`` and ``design``
    columns, after the checks of ``out``, ``resume`` and ``force`` (nothing written).

    Returns
    -------
    done : ndarray of bool (count,)
        The designs whose rows ``path`` holds (all False without ``resume``).
    on_disk : dict or None
        Those columns read back, when resumed.

    Raises
    ------
    ParameterError
        ``resume`` and ``force`` both; an existing ``out`` without either; a resume of another sweep.
    """
    done = np.zeros(count, dtype=bool)
    if path is None:
        return done, None
    check_format(path)
    if resume and force:
        raise ParameterError("resume, force: choose one (resume continues the file, force starts again)")
    exists = path.exists() or staging_path(path).exists()
    if exists and not (resume or force):
        raise ParameterError(f"out: '{path}' exists; resume=True continues it, force=True overwrites it")
    if not (exists and resume):
        return done, None
    check_sidecar(path, identity)
    return done_designs(path, columns, names, values), read_columns(path, [best_by, "status", "design"])
