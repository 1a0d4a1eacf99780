"""The robustness study's results: each method's settling time over the sampled machines, the benefit over
the paper profile, and the sensitivity ranking (:mod:`studies.robustness`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import spearmanr

from isolator import Band, Scenario

from .tolerances import Varied

__all__ = ["MethodSpread", "RobustnessStudy"]


@dataclass(frozen=True)
class MethodSpread:
    """One method's settling time over the sampled machines.

    Attributes
    ----------
    name : str
    nominal : float or None
        On the nominal machine [s].
    settling_time : ndarray (samples,)
        Largest settling time per machine [s]; NaN where a run tips, diverges or does not settle in time.
    """

    name: str
    nominal: float | None
    settling_time: np.ndarray

    def percentile(self, q: float) -> float:
        """The ``q``-th percentile [s] over the machines, counting a machine without a settling time as
        slower than any (NaN when more than ``100 - q`` % have none)."""
        values = np.where(np.isnan(self.settling_time), np.inf, self.settling_time)
        value = float(np.percentile(values, q, method="higher"))
        return value if math.isfinite(value) else math.nan

    @property
    def worst(self) -> float:
        """The slowest machine's settling time [s] (NaN if any machine has none)."""
        return math.nan if np.isnan(self.settling_time).any() else float(np.max(self.settling_time))

    @property
    def failed(self) -> int:
        """How many machines have no settling time."""
        return int(np.isnan(self.settling_time).sum())


@dataclass(frozen=True)
class RobustnessStudy:
    """The Monte Carlo study's machines and every method's settling on them.

    Attributes
    ----------
    scenario : Scenario
    varied : list of Varied
        The independently varied parameters (columns of ``samples``).
    samples : ndarray (samples, varied)
        Factors (relative tolerances) or values in the parameter's unit (absolute ones).
    methods : dict of str to MethodSpread
        ``paper``, ``ZVD``, ``optimised``.
    band : Band
        5 % of the paper profile's peaks on the nominal machine; every run is judged in it.
    folder : Path
    """

    scenario: Scenario
    varied: list[Varied]
    samples: np.ndarray
    methods: dict[str, MethodSpread]
    band: Band
    folder: Path

    def benefit(self, name: str) -> np.ndarray:
        """Per machine, how much sooner [s] method ``name`` settles than the paper profile (NaN where
        either has no settling time)."""
        return self.methods["paper"].settling_time - self.methods[name].settling_time

    def sensitivity(self, name: str) -> np.ndarray:
        """Spearman's rank correlation of each varied parameter with method ``name``'s settling time
        (machines without one left out; NaN where a column does not vary)."""
        y = self.methods[name].settling_time
        keep = ~np.isnan(y)
        rho = np.full(len(self.varied), np.nan)
        if keep.sum() < 3:
            return rho
        for j in range(len(self.varied)):
            x = self.samples[keep, j]
            if np.ptp(x) > 0 and np.ptp(y[keep]) > 0:
                rho[j] = float(spearmanr(x, y[keep]).statistic)
        return rho

    def ranking(self, name: str = "paper") -> list[tuple[str, float]]:
        """The varied parameters by how much they matter to ``name``'s settling time: (name, rho),
        largest |rho| first."""
        rho = self.sensitivity(name)
        order = np.argsort(-np.nan_to_num(np.abs(rho), nan=-1.0), kind="stable")
        return [(self.varied[j].name, float(rho[j])) for j in order]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the tolerances, the band and per method its P50, P95, worst and benefit spread."""
        out: dict[str, Any] = {
            "samples": int(self.samples.shape[0]),
            "tolerances": sorted({v.tolerance.label for v in self.varied}),
            "band": self.band.to_dict(),
            "methods": {},
        }
        for name, m in self.methods.items():
            entry: dict[str, Any] = {"nominal": m.nominal, "p50": _none(m.percentile(50)),
                                     "p95": _none(m.percentile(95)), "worst": _none(m.worst), "failed": m.failed,
                                     "sensitivity": dict(self.ranking(name))}
            if name != "paper":
                b = self.benefit(name)
                entry["benefit"] = {"p5": _none(_nanpct(b, 5)), "p50": _none(_nanpct(b, 50)),
                                    "p95": _none(_nanpct(b, 95)),
                                    "better_share": float(np.mean(b[~np.isnan(b)] > 0)) if np.any(~np.isnan(b))
                                    else None}
            out["methods"][name] = entry
        return out


def _none(value: float) -> float | None:
    return None if math.isnan(value) else value


def _nanpct(values: np.ndarray, q: float) -> float:
    known = values[~np.isnan(values)]
    return float(np.percentile(known, q)) if known.size else math.nan
