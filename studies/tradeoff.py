"""Floor isolation against settling: every isolator's stiffness and damping swept together.

Run it with ``isolator study tradeoff [SCENARIO] --out DIR``. Each design scales
the stiffness and the damping of every isolator (all axes) by two factors on
log grids; the scenario's own design is 1 x 1. For each design the study
measures

* the largest 5 % settling time of the scenario's carriage moves, from the
  exact time-varying simulation (one :func:`isolator.sweep.sweep` of transient runs;
  pneumatic tables: the settling about the slowly leveling table); with
  ``[[windows]]`` also the window settling time and the moves per hour of a
  machine repeating the move; with a ``[sequence]`` instead the sequence's total
  time and its steps per hour;
* the floor-to-table transmissibility of the table parked with the carriages
  at their start (linearised): the worst of the x, y and z same-axis values at
  a reference frequency (default 10 Hz: how much floor vibration gets through)
  and the worst resonance peak (how much the table amplifies near its modes).

Soft isolators isolate better and settle slower; damping shortens settling and
lowers the resonance peak but lets more high-frequency floor motion through.
The study writes

* ``maps.png``: settling time, transmissibility at the reference frequency and
  resonance peak over the (stiffness, damping) grid, tipping designs hatched;
* ``tradeoff.png``: settling time (or the sequence's total time) against
  transmissibility for every design, with the Pareto front and the scenario's design;
* ``throughput.png`` (with ``[[windows]]`` or a ``[sequence]``): transmissibility
  against moves (steps) per hour, with its own Pareto front;
* ``budget.png`` (with a random source: ``[ground.spectrum]``, ``[[disturbances]]``
  or an actuator's ``noise_psd``): the time figure against the passive error
  budget's displacement RMS at the tool (the first ``[[points]]`` entry, or the
  mass centre; the worst of x, y, z) and against the resonance peak, with their
  Pareto fronts (:mod:`studies.tradeoff_budget`);
* ``designs.csv``: every design's numbers;
* ``report.md``: the scenario's design, the Pareto-optimal designs, the best
  design at the scenario's transmissibility and at its settling time, and the
  assumptions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from isolator import Band, ParameterError, Scenario, ScenarioError, Simulator, UnstableTableError
from isolator.analysis.linear import linearise
from isolator.analysis.transmissibility import transmissibility
from isolator.scenario.arguments import check_public
from isolator.simulation.scaling import scale_columns
from isolator.sweep import SweepResult, sweep

from .reporting import output_folder, progress_printer
from .tradeoff_budget import budget_report, budget_tool, plot_budget, worst_axis
from .tradeoff_designs import write_designs_csv
from .tradeoff_report import plot_maps, plot_throughput, plot_tradeoff, write_tradeoff_report
from .tradeoff_results import TradeoffStudy, pareto_front

__all__ = ["TradeoffStudy", "pareto_front", "run_tradeoff_study", "tradeoff_sweep"]

#: default grids of scale factors on every isolator's stiffness and damping
STIFFNESS_SCALES = np.geomspace(0.25, 4.0, 17)
DAMPING_SCALES = np.geomspace(0.25, 8.0, 16)
_AXES = ("x", "y", "z")
#: longest time after the stop the runs are lengthened to [s] (a sequence: per step)
MAX_WINDOW = 60.0


def run_tradeoff_study(
    folder: str | Path,
    scenario: Scenario,
    stiffness: Sequence[float] | np.ndarray | None = None,
    damping: Sequence[float] | np.ndarray | None = None,
    reference_hz: float = 10.0,
    progress: bool = False,
    workers: int | None = None,
) -> TradeoffStudy:
    """Sweep the isolators' stiffness and damping; write figures, ``designs.csv`` and ``report.md``.

    Parameters
    ----------
    folder : str or Path
        The output folder (created if missing): figures, ``report.md`` and the study's data files.
    scenario : Scenario
        With carriage moves that stop (a sine never settles), or a ``[sequence]``.
    stiffness, damping : ndarray, optional
        Scale factors (> 0), increasing; default :data:`STIFFNESS_SCALES`, :data:`DAMPING_SCALES`.
    reference_hz : float
        Frequency of the transmissibility figure [Hz], > 0.
    progress : bool
        Print a line per stage on stderr (off by default; ``isolator study`` turns it on).
    workers : int, optional
        Processes of the sweep (default: the machine's cores; 1: in this process).

    Returns
    -------
    TradeoffStudy
        The grid of stiffness and damping factors, each design's settling time [s] and transmissibility, and
        the Pareto front.

    Raises
    ------
    ParameterError
        Bad scales or frequency.
    ScenarioError
        No carriages, or carriages that never stop.

    Examples
    --------
    >>> import tempfile
    >>> from isolator import load_scenario
    >>> from studies.tradeoff import run_tradeoff_study
    >>> study = run_tradeoff_study(tempfile.mkdtemp(), load_scenario("paper-table-3-2"), stiffness=[0.5, 1.0],
    ...                            damping=[1.0, 2.0], progress=False, workers=1)
    >>> study.settling_time.shape
    (2, 2)
    >>> study.pareto()  # (stiffness index, damping index) of the designs nothing beats in both
    [...]
    """
    k = _grid(STIFFNESS_SCALES if stiffness is None else stiffness, "stiffness")
    c = _grid(DAMPING_SCALES if damping is None else damping, "damping")
    if not (math.isfinite(reference_hz) and reference_hz > 0):
        raise ParameterError(f"reference_hz: must be a finite frequency > 0, got {reference_hz}")
    sim = Simulator(scenario)
    if not scenario.carriages:
        raise ScenarioError("carriages: none move, so there is no settling time to trade")
    if not math.isfinite(sim.stop_time):
        raise ScenarioError("carriages: the moves never stop (a sine), so there is no settling time to trade")
    out = output_folder(folder)
    say = progress_printer(progress)
    sequence = scenario.sequence is not None
    say(f"tradeoff: {k.size} x {c.size} designs of {scenario.name}; which stiffnesses tip ...")
    stable = np.array([_stands(sim, scale) for scale in k])
    n_runs = int(stable.sum()) * c.size
    say(f"transmissibility of the {n_runs} designs that stand ...")
    trans, peak, peak_hz, decay = (np.full((k.size, c.size), np.nan) for _ in range(4))
    done = 0
    for i in np.flatnonzero(stable):
        for j in range(c.size):
            trans[i, j], peak[i, j], peak_hz[i, j], decay[i, j] = _linear_figures(sim, k[i], c[j], reference_hz)
            done += 1
            if n_runs >= 10 and done % max(1, n_runs // 10) == 0:
                say(f"  transmissibility: {done}/{n_runs} designs")
    duration = _duration(scenario, sim.stop_time, decay if n_runs else None)
    if duration > scenario.simulation.duration * (1 + 1e-12):
        say(f"runs lengthened to {duration:.4g} s so that the least damped designs can settle")
    timed = replace(scenario, simulation=replace(scenario.simulation, duration=duration))
    shape = (k.size, c.size)
    settling, window, per_hour = (np.full(shape, np.nan) for _ in range(3))
    band = Band.from_settling(scenario.settling)
    widths = np.full((*shape, 6), np.nan)
    status = np.full(shape, "ok", dtype=object)
    status[~stable] = "tips"
    failures: dict[tuple[int, int], str] = {}
    tool = budget_tool(scenario)
    budget, budget_axis = np.full(shape, np.nan), np.full(shape, "", dtype=object)
    if n_runs:
        say(f"{'sequences' if sequence else 'transient runs'}{'' if tool is None else f' and error budgets at {tool}'}"
            f" of the {n_runs} designs that stand ...")
        kk, cc = np.meshgrid(k[stable], c, indexing="ij")
        rows = tradeoff_sweep(timed, kk.ravel(), cc.ravel(), band, workers, progress,
                              None if tool is None else [f"{tool}:{a}" for a in _AXES]).table()
        where = (np.repeat(np.flatnonzero(stable), c.size), np.tile(np.arange(c.size), int(stable.sum())))
        if tool is not None:
            budget[where], budget_axis[where] = worst_axis(np.column_stack([rows[f"budget:{tool}:{a}"] for a in _AXES]))
        time = "total_time" if sequence else "dynamic_settling_time_max" if scenario.is_pneumatic \
            else "settling_time_max"
        settling[where] = rows[time]
        if not sequence:
            widths[where] = np.column_stack([rows[f"band:{s}"] for s in ("x", "y", "z", "rx", "ry", "rz")])
        if "window_settling_time_max" in rows:
            window[where], per_hour[where] = rows["window_settling_time_max"], rows["moves_per_hour"]
        if sequence:
            per_hour[where] = rows["throughput_per_hour"]
        # a single move's "unsettled" is judged here by the study's own column (pneumatic: the dynamic settling)
        swept = rows["status"] if sequence else np.where(rows["status"] == "unsettled", "ok", rows["status"])
        status[where] = np.where((swept == "ok") & np.isnan(rows[time]), "no settling time", swept)
        failures = {(int(i), int(j)): str(why) for i, j, st, why in zip(*where, swept, rows["reason"],
                                                                       strict=True) if st != "ok"}
    study = TradeoffStudy(scenario, k, c, reference_hz, settling, trans, peak, peak_hz, stable, duration, failures, out,
                          band, widths, window, per_hour, status, sequence, budget, budget_axis, tool)
    plot_maps(study)
    plot_tradeoff(study)
    if study.has_throughput:
        plot_throughput(study)
    if study.has_budget:
        plot_budget(study)
    write_designs_csv(study)
    write_tradeoff_report(study, budget_report(study))
    return study


def tradeoff_sweep(scenario: Scenario, stiffness: np.ndarray, damping: np.ndarray, band: Band | None = None,
                   workers: int | None = None, progress: bool = False,
                   budget: Sequence[str] | None = None) -> SweepResult:
    """The study's designs as one :func:`isolator.sweep.sweep`, zipped: every isolator's stiffness and damping
    scaled by ``stiffness[r]`` and ``damping[r]`` [-] (the columns of
    :func:`isolator.simulation.scaling.scale_columns`: for air springs the volumes, the orifice and the
    horizontal springs and dampers), the designs' parameter vectors those of
    :func:`isolator.simulation.scaling.scaled_parameter_sets`; ``budget``: the sweep's error-budget columns
    (``"point:axis"`` entries), computed in its workers."""
    scale = scale_columns(Simulator(scenario).layout, np.asarray(stiffness, dtype=float),
                          np.asarray(damping, dtype=float))
    return sweep(scenario, scale={n: list(v) for n, v in scale.items()}, zip=True, band=band, workers=workers,
                 progress=progress, budget=budget)


def _duration(scenario: Scenario, stop_time: float, decay: np.ndarray | None) -> float:
    """How long the runs last [s]: long enough after the stop for the slowest-decaying design to settle (5 % of an
    amplitude no larger than the peak: ln 20 / decay rate, with a margin, at most :data:`MAX_WINDOW`); a
    ``[sequence]``'s limit lengthened by that much per step."""
    if decay is None:
        return scenario.simulation.duration
    needed = min(2.5 * math.log(20.0) / max(float(np.nanmin(decay)), 1e-9), MAX_WINDOW)
    if scenario.sequence is not None:
        return max(scenario.simulation.duration, scenario.sequence.start + len(scenario.sequence.steps) * (
            needed + scenario.sequence.measure + 2.0))
    return stop_time + max(scenario.simulation.duration - stop_time, needed)


def _grid(values: Sequence[float] | np.ndarray, name: str) -> np.ndarray:
    grid = np.atleast_1d(np.asarray(values, dtype=float))
    if grid.ndim != 1 or grid.size < 2:
        raise ParameterError(f"{name}: give at least two scale factors")
    if not np.all(np.isfinite(grid)) or np.any(grid <= 0) or np.any(np.diff(grid) <= 0):
        raise ParameterError(f"{name}: scale factors must be finite, > 0 and increasing")
    return grid


def _stands(sim: Simulator, stiffness: float) -> bool:
    """Whether the table stands with its carriages at their start and at their end (statics do not
    depend on damping)."""
    try:
        sim.equilibria(sim.scaled_parameters(stiffness, 1.0))
    except UnstableTableError:
        return False
    return True


def _linear_figures(sim: Simulator, stiffness: float, damping: float, reference_hz: float) -> tuple[float, ...]:
    """Worst x, y, z same-axis transmissibility at ``reference_hz``, worst resonance peak, its frequency
    [Hz], and the slowest mode's decay rate [1/s]."""
    lin = linearise(sim.scenario, parameters=sim.scaled_parameters(stiffness, damping))
    at = lin.frequency_response(np.array([reference_hz]), [f"ground:{a}" for a in _AXES], list(_AXES))[0]
    response = transmissibility(lin)
    peaks = [response.peak(a) for a in _AXES]
    worst = max(range(len(_AXES)), key=lambda n: peaks[n][0])
    decay = float(-np.max(lin.eigenvalues.real))
    return float(np.max(np.abs(np.diag(at)))), peaks[worst][0], peaks[worst][1], decay


check_public(globals())
