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
  marked, and of each method's benefit over the paper profile on the same machine, in cycle time (move +
  settling: a shaped move is longer, which counts against it);
* ``sensitivity.png``: which tolerances matter most: the rank correlation (Spearman) of each varied
  parameter with the settling time, per method;
* ``samples.csv``: every machine's parameters and each method's settling time;
* ``results.json`` and ``report.md``: P50, P95 and worst per method (percentiles as upper order
  statistics; a machine that does not settle counts as the slowest), the cycle time's, the benefit's
  spread, the ranking, the band and the tolerances.
"""

from __future__ import annotations

import contextlib
import csv
from collections.abc import Sequence
from concurrent.futures import Executor
from pathlib import Path
from typing import Any

import numpy as np

from controllers.profiles import ProfileSettings, command_time, evaluate_move, optimise_profiles, shaped_scenario
from isolator import Band, ParameterError, Scenario, ScenarioError, Simulator
from isolator.scenario.arguments import check_public
from isolator.scenario.output_files import atomic_output
from isolator.sweep import sweep
from isolator.sweep.cluster import connect

from .reporting import output_folder, progress_printer, write_json
from .robustness_report import plot_cdf, plot_sensitivity, write_robustness_report
from .robustness_results import MethodSpread, RobustnessStudy
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


def run_robustness_study(
    folder: str | Path,
    scenario: Scenario,
    tolerances: Sequence[str | Tolerance] | None = None,
    samples: int = 200,
    seed: int = 0,
    workers: int | None = None,
    progress: bool = False,
    optimiser: ProfileSettings | None = None,
    executor: Executor | None = None,
    scheduler: str | None = None,
    security: Any = None,
) -> RobustnessStudy:
    """Run the Monte Carlo study; write figures, ``samples.csv`` and ``report.md`` to ``folder``.

    Parameters
    ----------
    folder : str or Path
        The output folder (created if missing): figures, ``report.md`` and the study's data files.
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
        Progress lines and bars on stderr (off by default; ``isolator study`` turns it on).
    optimiser : ProfileSettings, optional
        Of the optimised profile (default: the settling-time objective on the nominal model).
    executor : concurrent.futures.Executor, optional
        Where the sweeps' chunks run (:func:`isolator.sweep.sweep`; default a local process pool).
    scheduler : str, optional
        Instead, a Dask scheduler's address: ``tls://HOST:PORT`` with ``security``, or ``tcp://HOST:PORT``
        (:func:`isolator.sweep.cluster.connect`, connected once before any work).
    security : distributed.Security, optional
        The TLS certificates of a ``tls://`` scheduler (:func:`isolator.sweep.cluster.tls_security`).

    Returns
    -------
    RobustnessStudy
        The machines drawn, each profile's settling time [s] on each, its percentiles and the tolerances'
        rank correlations.

    Raises
    ------
    ParameterError
        A tolerance that is malformed, names an unknown parameter or one that cannot vary; a scheduler that
        cannot be reached or refuses the certificates (named).
    ExecutorError
        The cluster was lost during a sweep.
    """
    if scheduler is not None and executor is not None:
        raise ParameterError("scheduler, executor: choose one (the scheduler's cluster runs the sweeps)")
    if security is not None and scheduler is None:
        raise ParameterError("security: the certificates of a tls:// scheduler: give scheduler= too")
    if scenario.sequence is not None:
        raise ScenarioError("sequence: the robustness study varies a single move (the carriages' profiles); "
                            "this scenario has a [sequence]: sweep its parameters with isolator sweep instead")
    given = DEFAULT_TOLERANCES if tolerances is None else tolerances
    parsed = [t if isinstance(t, Tolerance) else parse_tolerance(t) for t in given]
    sim = Simulator(scenario)
    varied = varied_parameters(parsed, sim.layout, sim.parameters, skip_missing=tolerances is None)
    values = draw_samples(varied, samples, seed)
    with contextlib.ExitStack() as cluster:
        if scheduler is not None:  # before any work or file
            client = connect(scheduler, security)
            cluster.callback(client.close)
            executor = client.get_executor()
        return _study(folder, scenario, varied, values, samples, workers, progress, optimiser, executor)


def _study(folder: str | Path, scenario: Scenario, varied: list[Varied], values: np.ndarray, samples: int,
           workers: int | None, progress: bool, optimiser: ProfileSettings | None,
           executor: Executor | None) -> RobustnessStudy:
    """The study of :func:`run_robustness_study`, its machines drawn."""
    say = progress_printer(progress)
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
        nominal = evaluate_move(sc, name, command, band=band)
        result = sweep(sc, set=absolute or None, scale=relative or None, zip=True, band=band, workers=workers,
                       progress=progress, executor=executor)
        # air springs: the settling about the leveling table, as evaluate_move measures the nominal machine
        column = "dynamic_settling_time_max" if sc.is_pneumatic else "settling_time_max"
        methods[name] = MethodSpread(name, nominal.settling_time_max, np.asarray(result[column], dtype=float),
                                     nominal.move_time)
    study = RobustnessStudy(scenario, varied, values, methods, band, out)
    _write_samples(study)
    write_json(out, study.to_dict())
    plot_cdf(study)
    plot_sensitivity(study)
    write_robustness_report(study)
    return study


def _write_samples(study: RobustnessStudy) -> Path:
    path = study.folder / "samples.csv"
    with atomic_output(path, newline="") as handle:
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


check_public(globals())
