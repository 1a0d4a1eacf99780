"""The robustness study's results: each method's settling time over the sampled machines, the benefit over
the paper profile, and the sensitivity ranking (:mod:`studies.robustness`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import rankdata, spearmanr

from isolator import Band, Scenario
from isolator.scenario.arguments import check_public

from .tolerances import Varied

__all__ = ["MethodSpread", "RobustnessStudy", "order_statistic", "upper_percentile"]


@dataclass(frozen=True)
class MethodSpread:
    """One method's settling time over the sampled machines.

    Attributes
    ----------
    name : str
    nominal : float or None
        Settling time on the nominal machine [s].
    settling_time : ndarray (samples,)
        Largest settling time per machine [s]; NaN where a run tips, diverges or does not settle in time.
    move_time : float
        The method's move, from the command to the stop [s] (prescribed: the same on every machine; a
        shaped move is longer than the paper's).
    """

    name: str
    nominal: float | None
    settling_time: np.ndarray
    move_time: float = 0.0

    @property
    def cycle_time(self) -> np.ndarray:
        """Move + settling per machine [s]; inf where the machine has no settling time."""
        return np.where(np.isnan(self.settling_time), np.inf, self.move_time + self.settling_time)

    def percentile(self, q: float, of: str = "settling") -> float:
        """The ``q``-th percentile [s] of the settling (``of="settling"``) or cycle time (``"cycle"``) over
        the machines: the upper order statistic (of the ``n`` sorted machines, the one of rank
        ``ceil(q/100 (n - 1)) + 1``, numpy's ``method="higher"``: with 20 machines or fewer P95 is the
        worst), a machine without a settling time counted as slower than any (NaN when the percentile falls
        on one)."""
        values = self.cycle_time if of == "cycle" else np.where(np.isnan(self.settling_time), np.inf,
                                                                 self.settling_time)
        return upper_percentile(values, q)

    @property
    def worst(self) -> float:
        """The slowest machine's settling time [s] (NaN if any machine has none)."""
        return math.nan if np.isnan(self.settling_time).any() else float(np.max(self.settling_time))

    @property
    def failed(self) -> int:
        """How many machines have no settling time."""
        return int(np.isnan(self.settling_time).sum())


def upper_percentile(values: np.ndarray, q: float) -> float:
    """The ``q``-th percentile of ``values`` as the upper order statistic (numpy ``method="higher"``),
    NaN entries left out; NaN when none is left or the percentile is infinite."""
    value = order_statistic(values, q, "higher")
    return value if math.isfinite(value) else math.nan


def order_statistic(values: np.ndarray, q: float, side: str) -> float:
    """The ``q``-th percentile of ``values`` (NaN entries left out) as the ``side`` ("higher" or "lower")
    order statistic, infinities kept; NaN when nothing is left."""
    known = np.asarray(values, dtype=float)
    known = known[~np.isnan(known)]
    if not known.size:
        return math.nan
    return float(np.percentile(known, q, method=side))  # type: ignore[call-overload]


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
        """Per machine, how much shorter [s] the cycle (move + settling) of method ``name`` is than the paper
        profile's: a longer shaped move counts against it. +inf where only the paper profile does not
        settle, -inf where only the method does not, NaN where neither does."""
        with np.errstate(invalid="ignore"):
            return self.methods["paper"].cycle_time - self.methods[name].cycle_time

    def sensitivity(self, name: str) -> np.ndarray:
        """Spearman's rank correlation of each varied parameter with method ``name``'s settling time, a
        machine without one ranked slowest (NaN where a column or the times do not vary)."""
        y = rankdata(np.where(np.isnan(self.methods[name].settling_time), np.inf, self.methods[name].settling_time))
        rho = np.full(len(self.varied), np.nan)
        if y.size < 3 or np.ptp(y) == 0:
            return rho
        for j in range(len(self.varied)):
            x = self.samples[:, j]
            if np.ptp(x) > 0:
                rho[j] = float(spearmanr(x, y).statistic)
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
            entry: dict[str, Any] = {"nominal": m.nominal, "move_time": m.move_time,
                                     "p50": _none(m.percentile(50)), "p95": _none(m.percentile(95)),
                                     "worst": _none(m.worst), "failed": m.failed,
                                     "cycle_p50": _none(m.percentile(50, "cycle")),
                                     "cycle_p95": _none(m.percentile(95, "cycle")),
                                     "sensitivity": dict(self.ranking(name))}
            if name != "paper":
                b = self.benefit(name)
                known = b[~np.isnan(b)]
                entry["benefit"] = {**{f"p{q}": _signed(order_statistic(b, q, "lower")) for q in (5, 50, 95)},
                                    "better_share": float(np.mean(known > 0)) if known.size else None,
                                    "compared": int(known.size),
                                    "only_paper_unsettled": int(np.isposinf(b).sum()),
                                    "only_method_unsettled": int(np.isneginf(b).sum())}
            out["methods"][name] = entry
        return out


def _signed(value: float) -> float | str | None:
    """A benefit for JSON: the number, "+inf"/"-inf" (only one of the two settles), or None (no machine)."""
    if math.isnan(value):
        return None
    return value if math.isfinite(value) else ("+inf" if value > 0 else "-inf")


def _none(value: float) -> float | None:
    return None if math.isnan(value) else value


check_public(globals())
