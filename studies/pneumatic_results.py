"""The pneumatic design study's results (:mod:`studies.pneumatic`): per design, per volume ratio, and the
closed form; :mod:`studies.pneumatic_report` writes them."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from isolator import Scenario
from isolator.scenario.arguments import check_public

from .tradeoff_results import pareto_front

__all__ = ["LONG_WINDOW", "MIN_WINDOW", "ClosedForm", "Optimum", "PneumaticStudy", "Transients"]

#: each run lasts at least this long after the carriages stop [s] (the valves re-level over seconds)
MIN_WINDOW = 15.0
#: designs not settled or not level within the first runs are run again this long after the stop [s]
LONG_WINDOW = 60.0


@dataclass(frozen=True)
class ClosedForm:
    """The optimal one-mass relaxation isolator at one volume ratio (:func:`studies.pneumatic.closed_form_optimum`).

    Attributes
    ----------
    ratio : float
        ``N = V2 / V1r`` [-].
    peak : float
        ``1 + 2 / N`` [m/m].
    relaxation_time : float
        Optimal ``tau`` [s].
    frequency_hz : float
        The fixed point, where the optimal peak is [Hz].
    diameter : float
        The orifice giving that ``tau`` [m].
    """

    ratio: float
    peak: float
    relaxation_time: float
    frequency_hz: float
    diameter: float


@dataclass(frozen=True)
class Optimum:
    """The orifice minimising the table's heave transmissibility peak at one volume ratio.

    Attributes
    ----------
    ratio : float
        ``N`` [-].
    diameter : float
        [m].
    peak : float
        The heave peak there [m/m].
    frequency_hz : float
        Its frequency [Hz].
    relaxation_time : float
        The isolators' relaxation time there, geometric mean of ``V2 / (n G p0)`` [s].
    at_edge : bool
        The search stopped at its bound beyond the grid (the optimum may lie further out).
    """

    ratio: float
    diameter: float
    peak: float
    frequency_hz: float
    relaxation_time: float
    at_edge: bool


@dataclass
class Transients:
    """The exact pneumatic runs' figures per design (NaN where not known).

    Attributes
    ----------
    settling : ndarray
        Dynamic 5 % settling time about the leveling table, largest of the six signals [s].
    contract_settling : ndarray
        The contract's 5 % settling time about the final level equilibrium [s].
    leveling : ndarray
        Largest leveling time over the valve groups [s]; NaN when a group is not level by the end.
    not_level : ndarray of bool
        Some group not level by the end of the run.
    exhausted : ndarray of bool
        Some group wanted air at its supply pressure.
    duration : ndarray
        Length of the run the figures are from [s] (NaN: not run).
    failures : dict
        ``(i, j) -> reason`` for runs that diverged.
    band : ndarray (..., 6)
        The band both settling times are measured in, per design: 5 % of that run's own peaks (the
        scenario's ``[settling]`` rule), six half-widths [m, rad] (NaN: not run).
    window : ndarray
        With ``[[windows]]``: the largest window settling time after the stop [s] (NaN: none, or not shown).
    per_hour : ndarray
        With ``[[windows]]``: moves per hour repeating the move and waiting for the windows [1/h].
    """

    settling: np.ndarray
    contract_settling: np.ndarray
    leveling: np.ndarray
    not_level: np.ndarray
    exhausted: np.ndarray
    duration: np.ndarray
    failures: dict[tuple[int, int], str] = field(default_factory=dict)
    band: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 6)))
    window: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    per_hour: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    @classmethod
    def empty(cls, shape: tuple[int, int]) -> Transients:
        """Nothing run yet on a grid of ``shape``."""
        return cls(np.full(shape, np.nan), np.full(shape, np.nan), np.full(shape, np.nan), np.zeros(shape, bool),
                   np.zeros(shape, bool), np.full(shape, np.nan), {}, np.full((*shape, 6), np.nan),
                   np.full(shape, np.nan), np.full(shape, np.nan))

    def record(self, ij: tuple[int, int], duration: float, contract: float | None, dynamic: float | None,
               levels: dict[str, float | None], exhausted: bool, band: tuple[float, ...] | None = None,
               window: float | None = None, per_hour: float | None = None) -> None:
        """One run's figures (None: not settled / not level), its band's half-widths [m, rad], and with
        ``[[windows]]`` its window settling time [s] and moves per hour [1/h]."""
        self.failures.pop(ij, None)
        if self.window.shape == self.settling.shape:
            self.window[ij] = math.nan if window is None else window
            self.per_hour[ij] = math.nan if per_hour is None else per_hour
        if self.band.shape[:-1] == self.settling.shape:
            self.band[ij] = math.nan if band is None else band
        self.duration[ij] = duration
        self.contract_settling[ij] = math.nan if contract is None else contract
        self.settling[ij] = math.nan if dynamic is None else dynamic
        known = [v for v in levels.values() if v is not None]
        self.not_level[ij] = len(known) < len(levels)
        self.leveling[ij] = max(known) if known and not self.not_level[ij] else math.nan
        self.exhausted[ij] = exhausted

    def record_failure(self, ij: tuple[int, int], duration: float, reason: str) -> None:
        """A run that diverged."""
        self.record(ij, duration, None, None, {}, False)
        self.failures[ij] = reason

    def unfinished(self, ij: tuple[int, int]) -> bool:
        """Run, not diverged, and not settled or some group not level."""
        return ij not in self.failures and bool(np.isnan(self.settling[ij]) or self.not_level[ij])

    def status(self, ij: tuple[int, int]) -> str:
        """``ok``, ``diverged``, ``not run`` or what is missing (``not settled``, ``not level``), and
        ``supply exhausted``."""
        if ij in self.failures:
            return "diverged"
        if np.isnan(self.duration[ij]):
            return "not run"
        notes = (["not settled"] if np.isnan(self.settling[ij]) else []) + (["not level"] if self.not_level[ij] else [])
        notes += ["supply exhausted"] if self.exhausted[ij] else []
        return "; ".join(notes) or "ok"


@dataclass(frozen=True)
class PneumaticStudy:
    """Every design's transmissibility, settling and leveling, and the optimal orifice per volume ratio.

    Arrays over the grid are ``(diameters.size, ratios.size)``.

    Attributes
    ----------
    scenario : Scenario
    diameters : ndarray
        Orifice diameters, every isolator's [m].
    ratios : ndarray
        Damping-chamber volume ratios ``N = V2 / V1r`` [-].
    reference_hz : float
        Frequency of the isolation figure [Hz].
    heave_peak, heave_peak_hz : ndarray
        Heave (z) transmissibility peak [m/m] and its frequency [Hz].
    rocking_peak, rocking_peak_hz : ndarray
        Worst of the rx and ry peaks [rad/rad] and its frequency [Hz].
    transmissibility : ndarray
        Worst same-axis x, y, z transmissibility at ``reference_hz`` [m/m].
    runs : Transients
        The exact runs' settling and leveling figures.
    tips : tuple of (int, int)
        Designs whose table cannot stand (no figures).
    optima : tuple of Optimum
        Per volume ratio.
    closed_form : tuple of ClosedForm
        Per volume ratio.
    moves : bool
        Whether the scenario's carriages move (else no runs).
    own_diameter, own_ratio : float
        The scenario's own design (geometric means over its isolators) [m], [-].
    own_linear : dict
        Its linear figures (``heave``, ``heave_hz``, ``rocking``, ``rocking_hz``, ``at_ref``, ``decay``).
    own_runs : Transients
        Its run's figures, a 1 x 1 grid.
    folder : Path
    """

    scenario: Scenario
    diameters: np.ndarray
    ratios: np.ndarray
    reference_hz: float
    heave_peak: np.ndarray
    heave_peak_hz: np.ndarray
    rocking_peak: np.ndarray
    rocking_peak_hz: np.ndarray
    transmissibility: np.ndarray
    runs: Transients
    tips: tuple[tuple[int, int], ...]
    optima: tuple[Optimum, ...]
    closed_form: tuple[ClosedForm, ...]
    moves: bool
    own_diameter: float
    own_ratio: float
    own_linear: dict[str, float]
    own_runs: Transients
    folder: Path = Path(".")

    @property
    def settling_time(self) -> np.ndarray:
        """The study's settling figure: dynamic 5 % settling time about the leveling table [s]."""
        return self.runs.settling

    @property
    def contract_settling_time(self) -> np.ndarray:
        """The contract's 5 % settling time about the final level equilibrium [s]."""
        return self.runs.contract_settling

    @property
    def leveling_time(self) -> np.ndarray:
        """Largest leveling time over the groups [s], NaN when one is not level by the end of its run."""
        return self.runs.leveling

    @property
    def optimal_diameter(self) -> np.ndarray:
        """Per volume ratio [m]."""
        return np.array([o.diameter for o in self.optima])

    @property
    def optimal_peak(self) -> np.ndarray:
        """The heave peak at the optimal diameter, per volume ratio [m/m]."""
        return np.array([o.peak for o in self.optima])

    def pareto(self) -> list[tuple[int, int]]:
        """Designs no other beats in both settling time and transmissibility, by increasing settling time."""
        points = np.column_stack([self.settling_time.ravel(), self.transmissibility.ravel()])
        nr = self.ratios.size
        return [(int(i) // nr, int(i) % nr) for i in pareto_front(points)]

    def nominal(self) -> tuple[int, int] | None:
        """Grid indices of the scenario's own design, if on the grid."""
        i = np.flatnonzero(np.isclose(self.diameters, self.own_diameter, rtol=1e-9))
        j = np.flatnonzero(np.isclose(self.ratios, self.own_ratio, rtol=1e-9))
        return (int(i[0]), int(j[0])) if i.size and j.size else None


check_public(globals())
