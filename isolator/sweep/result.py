"""What a sweep returns: its columns in design order (kept, or read back from the file it streamed to),
and a tally kept as the rows arrived (runs, failures, the best design)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.names import escaped
from isolator.sweep.output import TEXT_COLUMNS, read_columns
from isolator.sweep.worker import ChunkResult

__all__ = ["SweepResult", "Tally"]


@dataclass
class Tally:
    """Counts kept as rows arrive, without keeping the rows.

    Attributes
    ----------
    designs : int
        In the sweep.
    resumed : int
        Found on disk (not run again).
    runs : int
        Run by this call.
    failed : int
        Rows (all of them) whose status is not "ok".
    statuses : dict of str to int
        Those rows by status ("unsettled", "tipped", ...).
    best : int or None
        The design with the smallest :attr:`column` among those "ok" (None: none has one).
    best_time : float
        Its :attr:`column` [s].
    column : str
        What "best" is judged by: ``settling_time_max``, or a sequence's ``total_time``.
    metric : int or None
        Where :attr:`column` is among a chunk's ``metrics`` (None: ``settling_time_max``, from the settling).
    """

    designs: int
    resumed: int = 0
    runs: int = 0
    failed: int = 0
    statuses: dict[str, int] = field(default_factory=dict)
    best: int | None = None
    best_time: float = math.inf
    column: str = "settling_time_max"
    metric: int | None = None

    def add(self, result: ChunkResult) -> None:
        """Count a chunk's rows."""
        self.runs += result.status.size
        with np.errstate(all="ignore"):
            if self.metric is None:
                worst = np.where(np.all(np.isfinite(result.settling), axis=1), np.max(result.settling, axis=1),
                                 np.inf)
            else:
                worst = result.metrics[:, self.metric]
        self.count(result.start + np.arange(result.status.size), worst, result.status)

    def count(self, designs: np.ndarray, worst: np.ndarray, status: np.ndarray) -> None:
        """Count rows: their designs, :attr:`column` [s] (NaN or inf: none) and status."""
        ok = status == "ok"
        self.failed += int(np.sum(~ok))
        for kind, n in zip(*np.unique(np.asarray(status[~ok], dtype=str), return_counts=True), strict=True):
            self.statuses[str(kind)] = self.statuses.get(str(kind), 0) + int(n)
        value = np.where(ok & np.isfinite(worst), worst, np.inf)
        if value.size and np.min(value) < self.best_time:
            at = int(np.argmin(value))
            self.best, self.best_time = int(designs[at]), float(value[at])


@dataclass
class SweepResult:
    """The rows of a sweep, one per design in design order.

    Attributes
    ----------
    columns : tuple of str
        In output order (:func:`isolator.sweep.output.column_names`).
    names : tuple of str
        The swept names, as given.
    path : Path or None
        The file the rows were streamed to (the columns are read back from it).
    tally : Tally
    wall_time : float
        Of the call [s].
    scaled : tuple of str
        The swept names whose values are factors on the scenario's (``scale``), not values (``set``).

    Examples
    --------
    >>> from isolator.sweep import sweep
    >>> result = sweep("paper-table-3-2", scale={"isolators[*].damping": [0.5, 1, 2]}, workers=1)
    >>> result["settling_time_max"].round(2).tolist()  # NaN: that design does not settle within the run
    [nan, 2.31, 1.14]
    """

    columns: tuple[str, ...]
    names: tuple[str, ...]
    path: Path | None
    tally: Tally
    wall_time: float
    _kept: dict[str, np.ndarray] | None = field(default=None, repr=False)
    scaled: tuple[str, ...] = ()

    @classmethod
    def made(cls, columns: Sequence[str], names: Sequence[str], path: Path | None, rows: list[list[Any]] | None,
             tally: Tally, wall_time: float, scaled: Sequence[str] = ()) -> SweepResult:
        """From the rows kept in memory (``path`` None) or the file; ``scaled``: the names swept by factors."""
        kept = None
        if rows is not None:
            table = list(map(list, zip(*rows, strict=True))) if rows else [[] for _ in columns]
            kept = {c: (np.array(v, dtype=object) if c in TEXT_COLUMNS else np.array(v, dtype=float))
                    for c, v in zip(columns, table, strict=True)}
        return cls(tuple(columns), tuple(names), path, tally, wall_time, kept, tuple(scaled))

    def table(self) -> dict[str, np.ndarray]:
        """Every column by name: numbers as float arrays, ``status`` and ``reason`` as str (object) arrays."""
        if self._kept is not None:
            return dict(self._kept)
        assert self.path is not None
        return read_columns(self.path)

    def __getitem__(self, column: str) -> np.ndarray:
        if column not in self.columns:
            raise ParameterError(f"column: not a column of this sweep: {column!r} (columns: "
                                 f"{', '.join(self.columns[:len(self.names) + 2])}, ...)")
        if self._kept is not None:
            return self._kept[column]
        assert self.path is not None
        return read_columns(self.path, [column])[column]

    def __len__(self) -> int:
        return self.tally.designs

    @property
    def runs_per_second(self) -> float:
        """Designs run by this call per second of its wall time."""
        return self.tally.runs / self.wall_time if self.wall_time > 0 else math.nan

    def best(self) -> Mapping[str, float] | None:
        """The swept values and ``settling_time_max`` (a sequence: ``total_time``) of the design that settles
        (finishes) first (None: none did)."""
        if self.tally.best is None:
            return None
        values = {n: float(self[n][self._row(self.tally.best)]) for n in self.names}
        return {**values, self.tally.column: self.tally.best_time}

    def _row(self, design: int) -> int:
        rows = self["design"]
        return int(np.flatnonzero(rows == design)[0])

    def summary(self) -> str:
        """Runs, failures, wall time, runs/s and the best design, in a few lines."""
        t = self.tally
        kinds = ", ".join(f"{n} {kind}" for kind, n in sorted(t.statuses.items()))
        lines = [f"designs: {t.designs} ({t.runs} run now" + (f", {t.resumed} from the file" if t.resumed else "")
                 + f"), not ok: {t.failed}" + (f" ({kinds})" if kinds else ""),
                 f"wall time: {self.wall_time:.3g} s ({self.runs_per_second:.4g} runs/s)"]
        best = self.best()
        skipped = f" (of the {t.designs - t.failed} ok; skipped {kinds})" if t.failed else ""
        if best is not None:
            lines.append(f"best design{skipped}: " + ", ".join(f"{k} = {v:.6g}" for k, v in best.items()))
        else:
            lines.append(f"best design: none (no design is ok with a {t.column}; {kinds or 'no designs'})")
        if self.path is not None:
            lines.append(f"rows: {escaped(self.path)}")  # printed: a name's control characters escaped
        return "\n".join(lines)
