"""The error budget's result: every source's spectrum at every point and axis, their RMS, the total and the
cumulative RMS (``docs/scenario-format.md``, "Error budget"), with its JSON, CSV and figure."""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from isolator.scenario.output_files import atomic_output

from .units import AXES, QUANTITY_UNITS, display_unit

__all__ = ["AXES", "QUANTITY_UNITS", "ErrorBudget"]

#: how much above the passive table's RMS a closed loop's must be to count as worse (the integrals' accuracy)
WORSE = 1e-3

@dataclass(frozen=True)
class ErrorBudget:
    """Random motion at the points: each source's power spectral density, RMS and share.

    Attributes
    ----------
    quantity : {"displacement", "velocity", "acceleration"}
        Of the points' absolute motion along world axes [m, m/s, m/s^2].
    band : tuple of float
        ``(low, high)`` [Hz] integrated over.
    controller : str or None
        The exported controller's ``method``, None for the passive table.
    points : tuple of str
        Point names (``table``: the mass centre of a scenario without ``[[points]]``).
    sources : tuple of str
        ``floor:x``, ``force:<name>``, ``actuator:<name>``, ``sensor:<name>``.
    frequency : ndarray (nf,)
        [Hz], increasing, from ``band[0]`` to ``band[1]`` (placed where the resonances and the sources'
        corners are).
    psd : ndarray (points, 3, sources, nf)
        One-sided PSD of each source's part [SI^2/Hz].
    positions : ndarray
        The carriages' rest positions [m] the table was linearised at.
    passive_rms : ndarray (points, 3) or None
        With a controller: the passive table's total RMS over the same band [SI] (None without one).
    silent : tuple of str
        The sources with nothing inside the band (their density zero over it).
    relative : tuple of str
        ``A:B`` pairs of points whose relative elastic motion was budgeted (``--relative``).
    relative_psd : ndarray (pairs, 3, sources, nf) or None
        One-sided PSD of each source's part of ``A``'s elastic translation minus ``B``'s, table axes
        [SI^2/Hz] (zero on a rigid top).
    """

    quantity: str
    band: tuple[float, float]
    controller: str | None
    points: tuple[str, ...]
    sources: tuple[str, ...]
    frequency: np.ndarray
    psd: np.ndarray
    positions: np.ndarray
    passive_rms: np.ndarray | None = None
    silent: tuple[str, ...] = ()
    relative: tuple[str, ...] = ()
    relative_psd: np.ndarray | None = None

    @property
    def relative_rms(self) -> np.ndarray:
        """(pairs, 3, sources) RMS of each source's part of each pair's relative elastic motion [SI]."""
        if self.relative_psd is None:
            return np.zeros((0, 3, len(self.sources)))
        return np.sqrt(np.trapezoid(self.relative_psd, self.frequency, axis=-1))

    @property
    def unit(self) -> str:
        """SI unit of the quantity."""
        return QUANTITY_UNITS[self.quantity]

    @property
    def total_psd(self) -> np.ndarray:
        """(points, 3, nf) [SI^2/Hz]: the sum over the (uncorrelated) sources."""
        return np.asarray(self.psd.sum(axis=2))

    @property
    def asd(self) -> np.ndarray:
        """(points, 3, sources, nf) amplitude spectral density [SI/sqrt(Hz)]."""
        return np.sqrt(self.psd)

    @property
    def source_rms(self) -> np.ndarray:
        """(points, 3, sources) RMS of each source's part over the band [SI]."""
        return np.sqrt(np.trapezoid(self.psd, self.frequency, axis=-1))

    @property
    def rms(self) -> np.ndarray:
        """(points, 3) total RMS over the band [SI]: the root of the sum of the sources' squares."""
        return np.sqrt(np.trapezoid(self.total_psd, self.frequency, axis=-1))

    @property
    def cumulative(self) -> np.ndarray:
        """(points, 3, nf) RMS from the band's low edge up to each frequency [SI]; ends at :attr:`rms`."""
        total = self.total_psd
        steps = 0.5 * (total[..., 1:] + total[..., :-1]) * np.diff(self.frequency)
        return np.sqrt(np.concatenate([np.zeros((*total.shape[:2], 1)), np.cumsum(steps, axis=-1)], axis=-1))

    def value(self, point: str, axis: str, source: str | None = None) -> float:
        """The RMS [SI] at ``point`` along ``axis``: the total, or one source's part.

        Raises
        ------
        KeyError
            An unknown point, axis or source (its message names the known ones).
        """
        i, j = self._index(point, axis)
        if source is None:
            return float(self.rms[i, j])
        if source not in self.sources:
            raise KeyError(f"source: no source named {source!r} (have: {', '.join(self.sources)})")
        return float(self.source_rms[i, j, self.sources.index(source)])

    def _index(self, point: str, axis: str) -> tuple[int, int]:
        if point not in self.points:
            raise KeyError(f"point: no point named {point!r} in the budget (have: {', '.join(self.points)})")
        if axis not in AXES:
            raise KeyError(f"axis: must be one of x, y, z, got {axis!r}")
        return self.points.index(point), AXES.index(axis)

    def worse_than_passive(self) -> list[dict[str, Any]]:
        """Where the controller raises the RMS above the passive table's: ``{point, axis, passive, closed,
        largest}`` (RMS [SI], ``largest`` the closed loop's largest source) per point and axis, in order, where
        the closed loop's RMS exceeds the passive one's by more than :data:`WORSE` of it; empty without a
        controller or where it helps."""
        if self.passive_rms is None:
            return []
        rms, parts = self.rms, self.source_rms
        return [{"point": p, "axis": a, "passive": float(self.passive_rms[i, j]), "closed": float(rms[i, j]),
                 "largest": self.sources[int(np.argmax(parts[i, j]))]}
                for i, p in enumerate(self.points) for j, a in enumerate(AXES)
                if rms[i, j] > self.passive_rms[i, j] * (1 + WORSE)]

    def worse_lines(self) -> list[str]:
        """One line per entry of :meth:`worse_than_passive`, in readable units (what ``isolator budget`` warns)."""
        scale, unit = display_unit(self.quantity)
        return [f"{w['point']}:{w['axis']}: the closed loop's {w['closed'] * scale:.4g} {unit} RMS is above the "
                f"passive table's {w['passive'] * scale:.4g} {unit} (largest source {w['largest']})"
                for w in self.worse_than_passive()]

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``isolator budget --json``: ``quantity``, ``band``, ``controller``, ``points``
        ``{point: {axis: {"rms": total, "sources": {source: rms}}}}`` [SI], ``worse_than_passive``
        (:meth:`worse_than_passive`) and, with pairs budgeted, ``relative`` (the same form per ``A:B``)."""
        rms, parts = self.rms, self.source_rms
        return {
            "quantity": self.quantity,
            "band": [float(self.band[0]), float(self.band[1])],
            "controller": self.controller,
            "points": {p: {a: {"rms": float(rms[i, j]),
                               "sources": {s: float(parts[i, j, k]) for k, s in enumerate(self.sources)}}
                           for j, a in enumerate(AXES)}
                       for i, p in enumerate(self.points)},
            "worse_than_passive": self.worse_than_passive(),
            **({"relative": self._relative_dict()} if self.relative else {}),
        }

    def _relative_dict(self) -> dict[str, Any]:
        """``{"A:B": {axis: {"rms": total, "sources": {source: rms}}}}`` [SI]."""
        parts = self.relative_rms
        return {pair: {a: {"rms": float(np.sqrt(np.sum(parts[i, j] ** 2))),
                           "sources": {s: float(parts[i, j, k]) for k, s in enumerate(self.sources)}}
                       for j, a in enumerate(AXES)}
                for i, pair in enumerate(self.relative)}

    def columns(self) -> dict[str, np.ndarray]:
        """The CSV's columns: ``frequency_hz``, then per point and axis ``<point>:<axis>:<source>`` (ASD
        [SI/sqrt(Hz)]), ``<point>:<axis>:total`` (ASD) and ``<point>:<axis>:cumulative`` (RMS [SI]); then
        ``A:B:<axis>:<source>`` (ASD) per relative pair."""
        out = {"frequency_hz": self.frequency}
        asd, total, cumulative = self.asd, np.sqrt(self.total_psd), self.cumulative
        for i, p in enumerate(self.points):
            for j, a in enumerate(AXES):
                for k, s in enumerate(self.sources):
                    out[f"{p}:{a}:{s}"] = asd[i, j, k]
                out[f"{p}:{a}:total"] = total[i, j]
                out[f"{p}:{a}:cumulative"] = cumulative[i, j]
        if self.relative_psd is not None:
            for i, pair in enumerate(self.relative):
                for j, a in enumerate(AXES):
                    for k, s in enumerate(self.sources):
                        out[f"{pair}:{a}:{s}"] = np.sqrt(self.relative_psd[i, j, k])
        return out

    def to_csv(self, path: str | Path) -> Path:
        """Write :meth:`columns` to ``path`` (numbers at full precision); returns the path."""
        columns = self.columns()
        target = Path(path)
        with atomic_output(target, newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(list(columns))
            for row in np.column_stack(list(columns.values())):
                writer.writerow([repr(float(v)) for v in row])
        return target

    def summary_lines(self) -> list[str]:
        """The band, then one line per point and axis: the total RMS and the largest source, in readable units;
        then a note for each source with nothing inside the band."""
        scale, unit = display_unit(self.quantity)
        lines = [f"band {self.band[0]:g}-{self.band[1]:g} Hz"]
        rms, parts = self.rms, self.source_rms
        for i, p in enumerate(self.points):
            for j, a in enumerate(AXES):
                k = int(np.argmax(parts[i, j])) if self.sources else -1
                if k >= 0 and rms[i, j] > 0:
                    share = (parts[i, j, k] / rms[i, j]) ** 2
                    largest = f"; largest {self.sources[k]} ({share:.0%} of the square)"
                else:
                    largest = " (no source moves it inside the band)"
                lines.append(f"{p}:{a}: {rms[i, j] * scale:.4g} {unit} RMS{largest}")
        relative = self.relative_rms
        for i, pair in enumerate(self.relative):
            for j, a in enumerate(AXES):
                total = float(np.sqrt(np.sum(relative[i, j] ** 2)))
                k = int(np.argmax(relative[i, j])) if total > 0 else -1
                largest = f"; largest {self.sources[k]}" if k >= 0 else " (a rigid top: no relative motion)"
                lines.append(f"{pair}:e{a} (elastic, relative): {total * scale:.4g} {unit} RMS{largest}")
        lines += [f"note: {s} has nothing inside the band" for s in self.silent]
        return lines

    def plot(self, specification: dict[tuple[str, str], float] | None = None, title: str = "") -> Any:
        """The budget's figure (:func:`isolator.analysis.budget.figure.budget_figure`); returns it."""
        from .figure import budget_figure

        return budget_figure(self, specification or {}, title)

