"""The trade-off study's results (:mod:`studies.tradeoff`): every design's time figure, throughput and
transmissibility, and the Pareto fronts; :mod:`studies.tradeoff_report` draws and writes them."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from isolator import Band, Scenario
from isolator.scenario.arguments import check_public

from .reporting import design_band

__all__ = ["TradeoffStudy", "pareto_front"]


def pareto_front(points: np.ndarray) -> np.ndarray:
    """Indices of the rows of ``points`` (n, 2) not dominated by another row (both objectives
    minimised; rows with NaN take no part), sorted by the first objective.

    A row is dominated when another is no worse in both objectives and better in one.
    """
    points = np.asarray(points, dtype=float)
    valid = np.flatnonzero(np.all(np.isfinite(points), axis=1))
    order = valid[np.lexsort((points[valid, 1], points[valid, 0]))]
    front: list[int] = []
    best = math.inf
    for i in order:  # increasing first objective: kept when it improves the second
        if points[i, 1] < best:
            front.append(int(i))
            best = points[i, 1]
    return np.array(front, dtype=int)


@dataclass(frozen=True)
class TradeoffStudy:
    """Every design's settling time (or a sequence's total time), throughput and transmissibility.

    Attributes
    ----------
    scenario : Scenario
    stiffness, damping : ndarray (nk,), (nc,)
        Scale factors on every isolator's stiffness and damping.
    reference_hz : float
        Frequency of the transmissibility figure [Hz].
    settling_time : ndarray (nk, nc)
        The study's time figure [s]: the largest settling time in ``band`` (pneumatic tables: about the
        leveling table), or with a ``[sequence]`` its total time (first step's start to last step's end); NaN
        where a design tips, diverges or shows none.
    transmissibility : ndarray (nk, nc)
        Worst same-axis floor-to-table transmissibility of x, y, z at ``reference_hz`` [m/m].
    peak : ndarray (nk, nc)
        Worst same-axis resonance peak of x, y, z [m/m].
    peak_hz : ndarray (nk, nc)
        Its frequency [Hz].
    stable : ndarray (nk,) of bool
        False where the table tips at that stiffness (whatever the damping).
    duration : float
        Length of the transient runs [s] (the scenario's, or longer so that the least damped designs
        settle); with a ``[sequence]``, the longest the sequence may take.
    failures : dict
        ``(i, j) -> reason`` for designs whose run failed (tipped while moving, diverged, refused) or, with a
        ``[sequence]``, whose step did not settle.
    folder : Path
        Where the figures and the report are.
    band : Band
        The band rule: the scenario's ``[settling]`` (each design its own 5 %, as the paper).
    half_widths : ndarray (nk, nc, 6)
        The band each design's settling time is measured in [m, rad] (NaN: no run, or a sequence);
        :meth:`design_band`.
    window_settling : ndarray (nk, nc)
        With ``[[windows]]`` and a single move: the largest window settling time after the stop [s]; else NaN.
    per_hour : ndarray (nk, nc)
        Moves per hour of a machine repeating the move and waiting for the windows [1/h], or with a
        ``[sequence]`` its steps per hour; NaN without windows.
    status : ndarray (nk, nc) of str
        "ok", "tips" (no run), "no settling time", or the sweep's status of the run ("tipped", "diverged",
        "refused", "unsettled", ...).
    sequence : bool
        The scenario has a ``[sequence]`` (the time figure is its total time).
    budget_rms : ndarray (nk, nc)
        The passive error budget's displacement RMS at :attr:`budget_point` [m], the largest of x, y and z
        (:mod:`studies.tradeoff_budget`); NaN where the table tips (at rest or in its run) or without a random
        source.
    budget_axis : ndarray (nk, nc) of str
        Which axis that is ("" without a value).
    budget_point : str or None
        The tool: the first ``[[points]]`` entry (``table``, the mass centre, without points); None when the
        scenario has no random source (no budget).
    """

    scenario: Scenario
    stiffness: np.ndarray
    damping: np.ndarray
    reference_hz: float
    settling_time: np.ndarray
    transmissibility: np.ndarray
    peak: np.ndarray
    peak_hz: np.ndarray
    stable: np.ndarray
    duration: float
    failures: dict[tuple[int, int], str] = field(default_factory=dict)
    folder: Path = Path(".")
    band: Band = field(default_factory=Band)
    half_widths: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 6)))
    window_settling: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    per_hour: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    status: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), dtype=object))
    sequence: bool = False
    budget_rms: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    budget_axis: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), dtype=object))
    budget_point: str | None = None

    @property
    def time_label(self) -> str:
        """What the time figure is, in words."""
        return "total time of the sequence" if self.sequence else "largest settling time"

    @property
    def rate_label(self) -> str:
        """What :attr:`per_hour` counts."""
        return "steps per hour" if self.sequence else "moves per hour"

    @property
    def has_throughput(self) -> bool:
        """Whether the designs have a throughput (``[[windows]]`` or a ``[sequence]``, and a finite value)."""
        return bool(self.per_hour.size and np.any(np.isfinite(self.per_hour)))

    @property
    def has_budget(self) -> bool:
        """Whether the designs have an error budget (a random source and a finite value)."""
        return self.budget_point is not None and bool(self.budget_rms.size and np.any(np.isfinite(self.budget_rms)))

    def design_band(self, i: int, j: int) -> Band | None:
        """Design (i, j)'s band, resolved (None: no run)."""
        return design_band(self.band, self.half_widths[i, j])

    def _cells(self, front: np.ndarray) -> list[tuple[int, int]]:
        nc = self.damping.size
        return [(int(i) // nc, int(i) % nc) for i in front]

    def pareto(self) -> list[tuple[int, int]]:
        """The designs no other design beats in both the time figure and transmissibility, by increasing
        time."""
        return self._cells(pareto_front(np.column_stack([self.settling_time.ravel(),
                                                         self.transmissibility.ravel()])))

    def budget_pareto(self) -> list[tuple[int, int]]:
        """The designs no other design beats in both the time figure and the error budget at the tool, by
        increasing time (none without a budget)."""
        if not self.has_budget:
            return []
        return self._cells(pareto_front(np.column_stack([self.settling_time.ravel(), self.budget_rms.ravel()])))

    def peak_pareto(self) -> list[tuple[int, int]]:
        """The designs no other design beats in both the time figure and the resonance peak, by increasing
        time."""
        return self._cells(pareto_front(np.column_stack([self.settling_time.ravel(), self.peak.ravel()])))

    def throughput_pareto(self) -> list[tuple[int, int]]:
        """The designs no other design beats in both throughput (:attr:`per_hour`, maximised) and
        transmissibility (minimised), by decreasing throughput."""
        if not self.has_throughput:
            return []
        return self._cells(pareto_front(np.column_stack([-self.per_hour.ravel(), self.transmissibility.ravel()])))

    def nominal(self) -> tuple[int, int] | None:
        """Grid indices of the scenario's own design (scales 1 x 1), if on the grid."""
        i = np.flatnonzero(np.isclose(self.stiffness, 1.0, rtol=1e-9))
        j = np.flatnonzero(np.isclose(self.damping, 1.0, rtol=1e-9))
        return (int(i[0]), int(j[0])) if i.size and j.size else None


check_public(globals())
