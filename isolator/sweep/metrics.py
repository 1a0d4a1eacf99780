"""The metrics a sweep adds beyond the batch: designs of scenarios that are pneumatic, have ``[[windows]]`` or
have a ``[sequence]`` are each run on their own in the worker (:meth:`Simulator.run_method` from the designs'
equilibria, solved side by side, or :func:`~isolator.simulation.sequence.run_sequence`), and their rows get
the columns :func:`metric_columns` names."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from isolator.errors import ScenarioError, SimulationError, UnstableTableError
from isolator.scenario.definitions import SIGNALS, Scenario
from isolator.simulation.response import Response
from isolator.simulation.sequence import run_sequence
from isolator.simulation.settling import Band
from isolator.simulation.simulator import Simulator
from isolator.simulation.stepping import MAX_TURN

__all__ = ["PNEUMATIC_COLUMNS", "SEQUENCE_COLUMNS", "WINDOW_COLUMNS", "Runs", "metric_columns", "run_each",
           "run_each_sequence", "runs_alone"]

#: pneumatic scenarios: the settling about the leveling table [s], the largest leveling time over the valve
#: groups [s] (NaN when one is not level by the end, or there are none), 1 when a group wanted air at its supply
#: pressure (else 0)
PNEUMATIC_COLUMNS = ("dynamic_settling_time_max", "leveling_time", "supply_exhausted")
#: ``[[windows]]`` with a single move: the largest window settling time after the stop [s], and the moves per
#: hour a machine repeating the move and waiting for the windows makes [1/h]
WINDOW_COLUMNS = ("window_settling_time_max", "moves_per_hour")
#: ``[sequence]``: first step's start to last step's end [s], steps per hour [1/h], the step that did not
#: settle (NaN: none)
SEQUENCE_COLUMNS = ("total_time", "throughput_per_hour", "unsettled_step")


def runs_alone(scenario: Scenario) -> bool:
    """Whether a sweep runs each design of ``scenario`` on its own (pneumatic, windows or a sequence)."""
    return scenario.is_pneumatic or bool(scenario.windows) or scenario.sequence is not None


def metric_columns(scenario: Scenario) -> tuple[str, ...]:
    """The columns a sweep of ``scenario`` adds after ``band:<signal>``: :data:`SEQUENCE_COLUMNS` with a
    ``[sequence]``, else :data:`PNEUMATIC_COLUMNS` when pneumatic and :data:`WINDOW_COLUMNS` with windows."""
    if scenario.sequence is not None:
        return SEQUENCE_COLUMNS
    return (PNEUMATIC_COLUMNS if scenario.is_pneumatic else ()) + (WINDOW_COLUMNS if scenario.windows else ())


@dataclass(frozen=True)
class Runs:
    """The metrics of designs run one by one (arrays over the designs).

    Attributes
    ----------
    settling, peak, half_widths : ndarray (designs, 6)
        5 % settling times [s], peaks and the band's half-widths [m or rad]; NaN where unavailable.
    status, reason : ndarray (designs,) of str
    metrics : ndarray (designs, len(metric_columns))
    """

    settling: np.ndarray
    peak: np.ndarray
    half_widths: np.ndarray
    status: np.ndarray
    reason: np.ndarray
    metrics: np.ndarray

    @classmethod
    def empty(cls, n: int, width: int) -> Runs:
        return cls(np.full((n, 6), np.nan), np.full((n, 6), np.nan), np.full((n, 6), np.nan),
                   np.full(n, "ok", dtype=object), np.full(n, "", dtype=object), np.full((n, width), np.nan))


def _number(value: float | None) -> float:
    return math.nan if value is None else float(value)


def _single_metrics(scenario: Scenario, response: Response) -> list[float]:
    """The :func:`metric_columns` of one single-move run."""
    out: list[float] = []
    if scenario.is_pneumatic:
        pneumatic = response.pneumatic
        assert pneumatic is not None
        levels = list(pneumatic.leveling_time.values())
        known = [v for v in levels if v is not None]
        out += [_number(pneumatic.dynamic_settling_time_max),
                max(known) if known and len(known) == len(levels) else math.nan,
                1.0 if pneumatic.supply_exhausted else 0.0]
    if scenario.windows:
        out += [_number(response.window_settling_time_max), _number(response.moves_per_hour)]
    return out


def run_each(sim: Simulator, params: np.ndarray, band: Band | None) -> Runs:
    """Each design (rows of ``params``, whole parameter vectors) run on its own, as
    ``Simulator.run(p=...)`` runs it (without its tipping check: a design without a stable rest, or that turns
    past 0.2 rad, is "tipped", as in a batch), with the statuses of :func:`~isolator.simulation.batch.run_batch`
    (``diverged="record"``)."""
    n = params.shape[0]
    columns = metric_columns(sim.scenario)
    out = Runs.empty(n, len(columns))
    rule = Band.from_settling(sim.scenario.settling) if band is None else band

    def failed(i: int, exc: Exception, kind: str) -> None:
        out.status[i], out.reason[i] = kind, str(exc)

    for i in range(n):
        try:
            start, end = sim.equilibria(params[i])
        except UnstableTableError as exc:
            failed(i, exc, "tipped")
            continue
        except SimulationError as exc:
            failed(i, exc, "diverged")
            continue
        try:
            method = sim.method_for(max(start.max_frequency, end.max_frequency if end else 0.0))
        except ScenarioError as exc:  # far too many steps
            failed(i, exc, "refused")
            continue
        try:
            response = sim.run_method(params[i], start, end, method, band=rule)
            out.metrics[i] = _single_metrics(sim.scenario, response)
        except SimulationError as exc:
            failed(i, exc, "tipped" if f"turned by more than {MAX_TURN:g} rad" in str(exc) else "diverged")
            continue
        out.settling[i] = [_number(response.settling[s].time) for s in SIGNALS]
        out.peak[i] = [response.settling[s].peak for s in SIGNALS]
        out.half_widths[i] = response.band.half_widths
    return out


def run_each_sequence(scenario: Scenario, model: str, params: np.ndarray) -> Runs:
    """Each design's ``[sequence]`` (:func:`run_sequence` with ``parameters=``): :data:`SEQUENCE_COLUMNS`, the
    5 % settling columns NaN; status "unsettled" (the reason names the step) when a step does not settle within
    ``[simulation] duration``, "tipped" (a configuration without a stable rest), "diverged", "refused" (far too
    many steps)."""
    n = params.shape[0]
    out = Runs.empty(n, len(SEQUENCE_COLUMNS))
    for i, p in enumerate(params):
        try:
            result = run_sequence(scenario, model, parameters=p)
        except UnstableTableError as exc:
            out.status[i], out.reason[i] = "tipped", str(exc)
            continue
        except SimulationError as exc:
            out.status[i], out.reason[i] = "diverged", str(exc)
            continue
        except ScenarioError as exc:
            out.status[i], out.reason[i] = "refused", str(exc)
            continue
        if result.unsettled is not None:
            out.status[i] = "unsettled"
            out.reason[i] = (f"step {result.unsettled} did not settle within the run's {result.duration:g} s "
                             "([simulation] duration)")
        out.metrics[i] = [_number(result.total_time), _number(result.throughput),
                          math.nan if result.unsettled is None else float(result.unsettled)]
    return out
