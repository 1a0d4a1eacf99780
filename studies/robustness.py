"""Robustness (Monte Carlo): how the settling time spreads when the built machine differs from the drawing.

Run it with ``isolator study robustness [SCENARIO] --out DIR [--tolerance NAME=+-5% ...] [--samples N]``.
Masses, isolator stiffness, damping and positions vary within tolerances (:mod:`studies.tolerances`: each
element on its own, uniform, Latin-hypercube samples); the same machines are run with three ways of
moving the carriages: the scenario's own ("paper") profile, the ZVD-shaped one and the profile optimised
for the settling time on the nominal model. Every run goes through :func:`isolator.sweep.sweep`, and all
are judged in one band: 5 % of the paper profile's peaks on the nominal machine (kind ``baseline``, so a
method is not rewarded for a band of its own and the spread is the spread of the settling, not of the
band). The study writes

* ``cdf.png``: the distribution (empirical CDF) of the largest settling time per method, P50 and P95
  marked, and of each method's benefit over the paper profile on the same machine;
* ``sensitivity.png``: which tolerances matter most: the rank correlation (Spearman) of each varied
  parameter with the settling time, per method;
* ``samples.csv``: every machine's parameters and each method's settling time;
* ``results.json`` and ``report.md``: P50, P95 and worst per method, the benefit's spread, the ranking,
  the band and the tolerances.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import spearmanr

from controllers.profiles import ProfileSettings, command_time, evaluate_move, optimise_profiles, shaped_scenario
from isolator import Band, ParameterError, Scenario, Simulator
from isolator.sweep import sweep

from .reporting import output_folder, progress_printer, write_json
from .robustness_report import plot_cdf, plot_sensitivity, write_robustness_report
from .tolerances import (
    DEFAULT_TOLERANCES,
    Tolerance,
    Varied,
    draw_samples,
    parse_tolerance,
    sweep_columns,
    varied_parameters,
)

__all__ = ["METHODS", "MethodSpread", "RobustnessStudy", "run_robustness_study"]

#: the ways of moving the carriages compared (the scenario's own profile first)
METHODS = ("paper", "ZVD", "optimised")


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


def run_robustness_study(
    folder: str | Path,
    scenario: Scenario,
    tolerances: Sequence[str | Tolerance] | None = None,
    samples: int = 200,
    seed: int = 0,
    workers: int | None = None,
    progress: bool = True,
    optimiser: ProfileSettings | None = None,
) -> RobustnessStudy:
    """Run the Monte Carlo study; write figures, ``samples.csv`` and ``report.md`` to ``folder``.

    Parameters
    ----------
    folder : str or Path
    scenario : Scenario
        Carriages with trapezoids or S-curves (the "paper" profile).
    tolerances : sequence of str or Tolerance, optional
        ``NAME=+-5%`` / ``NAME=+-0.002`` (default :data:`DEFAULT_TOLERANCES`, those the scenario has).
    samples : int
        Machines drawn (Latin hypercube).
    seed : int
        Of the sampling.
    workers : int, optional
        Processes of the sweeps (default: the machine's cores).
    progress : bool
        Progress lines and bars.
    optimiser : ProfileSettings, optional
        Of the optimised profile (default: the settling-time objective on the nominal model).

    Raises
    ------
    ParameterError
        A tolerance that is malformed, names an unknown parameter or one that cannot vary.
    """
    say = progress_printer(progress)
    given = DEFAULT_TOLERANCES if tolerances is None else tolerances
    parsed = [t if isinstance(t, Tolerance) else parse_tolerance(t) for t in given]
    sim = Simulator(scenario)
    varied = varied_parameters(parsed, sim.layout, sim.parameters, skip_missing=tolerances is None)
    values = draw_samples(varied, samples, seed)
    out = output_folder(folder)
    command = command_time(scenario)
    paper = evaluate_move(scenario, "paper", command)
    band = Band.of_baseline("paper", paper.peak)
    say("optimising the profile on the nominal machine ...")
    optimised = optimise_profiles(scenario, optimiser or ProfileSettings(objective="settling"), progress=progress)
    scenarios = {"paper": scenario, "ZVD": shaped_scenario(scenario, "zvd", list(paper.peak.values())),
                 "optimised": optimised.scenario}
    absolute, relative = sweep_columns(varied, values)
    methods: dict[str, MethodSpread] = {}
    for name, sc in scenarios.items():
        say(f"{name}: {samples} machines ...")
        nominal = evaluate_move(sc, name, command, band=band).settling_time_max
        result = sweep(sc, set=absolute or None, scale=relative or None, zip=True, band=band, workers=workers,
                       progress=progress)
        methods[name] = MethodSpread(name, nominal, np.asarray(result["settling_time_max"], dtype=float))
    study = RobustnessStudy(scenario, varied, values, methods, band, out)
    _write_samples(study)
    write_json(out, study.to_dict())
    plot_cdf(study)
    plot_sensitivity(study)
    write_robustness_report(study)
    return study


def _write_samples(study: RobustnessStudy) -> Path:
    path = study.folder / "samples.csv"
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["machine", *(v.name + (" (factor)" if v.relative else "") for v in study.varied),
                         *(f"settling:{name}" for name in study.methods)])
        for i, row in enumerate(study.samples):
            writer.writerow([i, *(f"{x:.9g}" for x in row),
                             *("" if np.isnan(m.settling_time[i]) else f"{m.settling_time[i]:.6g}"
                               for m in study.methods.values())])
    return path


def parse_tolerances(texts: Sequence[str] | None) -> list[Tolerance] | None:
    """The ``--tolerance`` options parsed (None: the defaults)."""
    if not texts:
        return None
    if len(set(texts)) != len(texts):
        raise ParameterError("--tolerance: a tolerance is given twice")
    return [parse_tolerance(t) for t in texts]
