"""Air-spring design: the orifice and the damping-chamber volume of every pneumatic isolator swept together.

Run it with ``isolator study pneumatic [SCENARIO] --out DIR``. Each design gives every
isolator one orifice diameter ``d`` (log grid around the scenario's own) and one
volume ratio ``N = V2 / V1r`` (its damping chamber ``N`` times its spring chamber).
For each design the study measures, on the table parked with the carriages at
their start and linearised (valves closed, chamber pressures as states):

* the heave (z) transmissibility peak and the rocking peak (the worst of rx, ry);
* the worst same-axis translational (x, y, z) transmissibility at a reference
  frequency (default 10 Hz);

and from the exact pneumatic run of the scenario's moves (valves leveling):

* the 5 % settling time about the slowly leveling table
  (``Response.pneumatic.dynamic_settling_time_max``, the study's settling figure) and the
  contract's settling time about the final level equilibrium (``settling_time_max``);
* the leveling time, the largest over the valve groups (NaN when a group is not level by
  the end of the run);
* with ``[[windows]]``, the window settling time and the moves per hour of a machine repeating
  the move (``3600 / (move time + window settling time)``).

The runs are one :func:`isolator.sweep.sweep` over the designs' orifice diameters and
damping-chamber volumes (and one more, longer, for the designs not settled or not level).

Per volume ratio it then refines the orifice that minimises the heave peak beyond the grid
(a bounded 1-D minimisation in log diameter, linearisation only) and sets it beside the
closed form of a one-mass relaxation (Zener) isolator, :func:`closed_form_optimum`.
The results: :mod:`studies.pneumatic_results`; figures, ``designs.csv`` and ``report.md``:
:mod:`studies.pneumatic_report`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.optimize import minimize_scalar

from isolator import Scenario, Simulator, UnstableTableError
from isolator.analysis.linear import linearise
from isolator.analysis.transmissibility import default_frequencies, transmissibility
from isolator.errors import ParameterError
from isolator.model.parameters import ParameterLayout
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import SIGNALS
from isolator.scenario.pneumatic import PneumaticIsolator
from isolator.scenario.profiles import SineProfile
from isolator.scenario.validation import isolator_rest_pressures
from isolator.sweep import sweep

from .pneumatic_report import write_outputs
from .pneumatic_results import LONG_WINDOW, MIN_WINDOW, ClosedForm, Optimum, PneumaticStudy, Transients
from .reporting import output_folder, progress_printer

__all__ = [
    "DIAMETER_SCALES",
    "RATIOS",
    "ClosedForm",
    "PneumaticStudy",
    "closed_form_optimum",
    "default_diameters",
    "heave_peak",
    "relaxation_time_of",
    "run_pneumatic_study",
]

#: default orifice diameters, as factors on the scenario's own
DIAMETER_SCALES = np.geomspace(0.4, 2.5, 15)
#: default damping-chamber volume ratios N = V2 / V1r (2 ** -1 .. 2 ** 3, 2 among them)
RATIOS = 2.0 ** np.linspace(-1.0, 3.0, 11)
#: an optimum searched beyond the grid's end reaches this factor past it
EDGE_STRETCH = 2.0
_TRANSLATIONS = ("x", "y", "z")


def default_diameters(scenario: Scenario) -> np.ndarray:
    """The default orifice diameters [m]: :data:`DIAMETER_SCALES` times the geometric mean of the
    scenario's own orifice diameters."""
    return DIAMETER_SCALES * _own_diameter(_pneumatic_isolators(scenario))


def closed_form_optimum(scenario: Scenario, ratio: float) -> ClosedForm:
    """The optimal relaxation isolator of the table in heave, as one mass on one air spring.

    The one-mass model: the table's whole mass ``m`` on the isolators' summed static stiffness
    ``k0 = sum n p0 A^2 / (V1r (1 + N))`` (each at its group's rest pressure ``p0``, absolute,
    carriages at their start), ``k_inf = (1 + N) k0``. Its transmissibility
    ``|T|^2 = (1 + x^2) / ((1 - r (1 + N))^2 + x^2 (1 - r)^2)``, ``r = m w^2 / k_inf``,
    ``x = w tau``, passes for every ``tau`` through the fixed point ``r = 2 / (N + 2)``,
    ``w*^2 = 2 k0 (N + 1) / (m (N + 2))``, where ``|T| = 1 + 2 / N``. There ``d|T|^2/dw = 0``
    reduces (``a = 1 - r (1 + N) = -(1 - r)``) to ``x^2 = 1 + N``: the optimal relaxation time
    is ``tau = sqrt(1 + N) / w* = sqrt(m (N + 2) / (2 k0))``, the peak then at the fixed point.

    Each isolator's ``tau_k = N V1r_k / (n G p0_k)`` with ``G = pi d^4 / (128 mu L_k)``; the
    diameter given is the one whose geometric mean of ``tau_k`` over the isolators is ``tau``
    (exact when they are alike).

    Parameters
    ----------
    scenario : Scenario
        Pneumatic, every isolator with a damping chamber and an orifice.
    ratio : float
        ``N = V2 / V1r`` [-], > 0.

    Returns
    -------
    ClosedForm
    """
    if not (math.isfinite(ratio) and ratio > 0):
        raise ParameterError(f"ratio: must be a finite volume ratio > 0, got {ratio}")
    isolators = _pneumatic_isolators(scenario)
    air = scenario.air
    assert air is not None
    p0 = isolator_rest_pressures(scenario) + air.atmosphere
    n = air.polytropic
    k0 = sum(n * p * iso.area**2 / (iso.volume * (1 + ratio)) for iso, p in zip(isolators, p0, strict=True))
    m = scenario.total_mass
    omega = math.sqrt(2 * k0 * (ratio + 1) / (m * (ratio + 2)))
    tau = math.sqrt(1 + ratio) / omega
    diameter = (_tau_coefficient(scenario, ratio) / tau) ** 0.25
    return ClosedForm(ratio, 1 + 2 / ratio, tau, omega / (2 * math.pi), diameter)


def relaxation_time_of(scenario: Scenario, diameter: float, ratio: float) -> float:
    """Geometric mean over the isolators of ``tau_k = N V1r_k / (n G(d) p0_k)`` [s] with every orifice
    ``diameter`` [m] and every damping chamber ``ratio`` times its spring chamber (carriages at their start)."""
    return _tau_coefficient(scenario, ratio) / diameter**4


def heave_peak(scenario: Scenario, p: np.ndarray) -> tuple[float, float]:
    """The heave (z) transmissibility peak [m/m] and its frequency [Hz] of the table with parameters ``p``,
    parked with the carriages at their start (valves closed)."""
    lin = linearise(scenario, parameters=p)
    return transmissibility(lin, default_frequencies(lin, 400)).peak("z")


def run_pneumatic_study(
    folder: str | Path,
    scenario: Scenario,
    diameters: Sequence[float] | np.ndarray | None = None,
    ratios: Sequence[float] | np.ndarray | None = None,
    reference_hz: float = 10.0,
    progress: bool = False,
    workers: int | None = None,
) -> PneumaticStudy:
    """Sweep every isolator's orifice and damping-chamber volume; write figures, ``designs.csv``, ``report.md``.

    Parameters
    ----------
    folder : str or Path
        The output folder (created if missing): figures, ``report.md`` and the study's data files.
    scenario : Scenario
        With pneumatic isolators, each with a damping chamber and an orifice, and carriage
        moves that stop (without carriages only the linear figures and the optima are computed).
    diameters : ndarray, optional
        Orifice diameters [m] (> 0, increasing, at least two); default :func:`default_diameters`.
    ratios : ndarray, optional
        Volume ratios ``N = V2 / V1r`` [-] (> 0, increasing, at least two); default :data:`RATIOS`.
    reference_hz : float
        Frequency of the isolation figure [Hz], > 0.
    progress : bool
        Print a line per stage on stderr (off by default; ``isolator study`` turns it on).
    workers : int, optional
        Processes of the runs' sweeps (default: the machine's cores; 1: in this process).

    Returns
    -------
    PneumaticStudy
        The grid of orifice diameters and volume ratios, each design's peaks, settling and leveling times,
        the optimal orifice per ratio and the Pareto front.

    Raises
    ------
    ParameterError
        Bad diameters, ratios or frequency; a scenario that is not pneumatic, has an isolator
        without a damping chamber, or a move that never stops.
    """
    isolators = _pneumatic_isolators(scenario)
    d = _grid(default_diameters(scenario) if diameters is None else diameters, "diameters")
    N = _grid(RATIOS if ratios is None else ratios, "ratios")
    if not (math.isfinite(reference_hz) and reference_hz > 0):
        raise ParameterError(f"reference_hz: must be a finite frequency > 0 Hz, got {reference_hz}")
    if not math.isfinite(scenario.stop_time):
        moving = [c.name for c in scenario.carriages if isinstance(c.profile, SineProfile)]
        raise ParameterError(f"scenario: carriage '{', '.join(moving)}' moves as a sine and never stops, "
                             "so there is no settling or leveling time to study")
    out = output_folder(folder)
    say = progress_printer(progress)
    sim = Simulator(scenario)
    moves = bool(scenario.carriages) and scenario.stop_time > 0
    say(f"pneumatic: {d.size} orifice diameters x {N.size} volume ratios of {scenario.name}; "
        "linearised transmissibility ...")
    shape = (d.size, N.size)
    linear = {k: np.full(shape, np.nan) for k in ("heave", "heave_hz", "rocking", "rocking_hz", "at_ref", "decay")}
    params: dict[tuple[int, int], np.ndarray] = {}
    tips: list[tuple[int, int]] = []
    for i, di in enumerate(d):
        for j, Nj in enumerate(N):
            params[i, j] = _design(sim, isolators, di, Nj)
            try:
                figures = _linear_figures(scenario, params[i, j], reference_hz)
            except UnstableTableError:
                tips.append((i, j))
                continue
            for key, value in figures.items():
                linear[key][i, j] = value
    say("optimal orifice per volume ratio (heave peak, refined beyond the grid) ...")
    optima = [_optimum(sim, isolators, d, linear["heave"][:, j], Nj) for j, Nj in enumerate(N)]
    closed = [closed_form_optimum(scenario, float(Nj)) for Nj in N]
    own_p = sim.parameters
    own_linear = _linear_figures(scenario, own_p, reference_hz)
    transients = Transients.empty(shape)
    own_runs = Transients.empty((1, 1))
    if moves:
        base = max(scenario.simulation.duration, scenario.stop_time + MIN_WINDOW)
        todo = [(transients, ij, params[ij]) for ij in params if ij not in tips] + [(own_runs, (0, 0), own_p)]
        say(f"pneumatic runs of {len(todo) - 1} designs and the scenario's own, {base:.3g} s each ...")
        _run_designs(scenario, base, todo, say, workers)
        # a longer run for the slow ones; not for those whose valves ran out of supply (they did not level
        # in longer runs either, and they are the costly, stiff ones), except the scenario's own
        again = [(runs, ij, p) for runs, ij, p in todo
                 if runs.unfinished(ij) and (runs is own_runs or not runs.exhausted[ij])]
        if again:
            long = scenario.stop_time + LONG_WINDOW
            say(f"{len(again)} designs not settled or not level after {base:.3g} s: run again for {long:.3g} s ...")
            _run_designs(scenario, long, again, say, workers)
    else:
        say("no carriage moves: no settling or leveling times, transmissibility and optima only")
    study = PneumaticStudy(
        scenario=scenario, diameters=d, ratios=N, reference_hz=reference_hz,
        heave_peak=linear["heave"], heave_peak_hz=linear["heave_hz"], rocking_peak=linear["rocking"],
        rocking_peak_hz=linear["rocking_hz"], transmissibility=linear["at_ref"], runs=transients,
        tips=tuple(tips), optima=tuple(optima), closed_form=tuple(closed), moves=moves,
        own_diameter=_own_diameter(isolators), own_ratio=_own_ratio(isolators), own_linear=own_linear,
        own_runs=own_runs, folder=out,
    )
    write_outputs(study)
    say(f"written: {out / 'report.md'}")
    return study


# -- the designs ---------------------------------------------------------------------------------


def _pneumatic_isolators(scenario: Scenario) -> list[PneumaticIsolator]:
    if not scenario.is_pneumatic:
        raise ParameterError(f"scenario: the pneumatic study needs pneumatic isolators; '{scenario.name}' has "
                             "spring-damper isolators (try `isolator study tradeoff`)")
    isolators = [iso for iso in scenario.isolators if isinstance(iso, PneumaticIsolator)]
    for k, iso in enumerate(isolators):
        if not iso.has_damping_chamber or iso.orifice is None:
            raise ParameterError(f"scenario: isolators[{k}] '{iso.name}' has no damping chamber and orifice; "
                                 "the pneumatic study sizes both on every isolator")
    return isolators


def _own_diameter(isolators: Sequence[PneumaticIsolator]) -> float:
    return float(np.exp(np.mean([math.log(iso.orifice.diameter) for iso in isolators if iso.orifice])))


def _own_ratio(isolators: Sequence[PneumaticIsolator]) -> float:
    return float(np.exp(np.mean([math.log(iso.damping_volume / iso.volume) for iso in isolators])))


def _tau_coefficient(scenario: Scenario, ratio: float) -> float:
    """``c`` with ``tau = c / d^4`` [s m^4], ``tau`` the geometric mean of the isolators' relaxation times."""
    air = scenario.air
    assert air is not None
    p0 = isolator_rest_pressures(scenario) + air.atmosphere
    logs = [math.log(128 * air.viscosity * iso.orifice.length * ratio * iso.volume / (math.pi * air.polytropic * p))
            for iso, p in zip(_pneumatic_isolators(scenario), p0, strict=True) if iso.orifice is not None]
    return math.exp(float(np.mean(logs)))


def _grid(values: Sequence[float] | np.ndarray, name: str) -> np.ndarray:
    grid = np.atleast_1d(np.asarray(values, dtype=float))
    if grid.ndim != 1 or grid.size < 2:
        raise ParameterError(f"{name}: give at least two values, got {grid.size}")
    if not np.all(np.isfinite(grid)) or np.any(grid <= 0):
        bad = grid[~(np.isfinite(grid) & (grid > 0))][0]
        raise ParameterError(f"{name}: must be finite and > 0, got {bad:g}")
    if np.any(np.diff(grid) <= 0):
        raise ParameterError(f"{name}: must be increasing")
    return grid


def _design(sim: Simulator, isolators: Sequence[PneumaticIsolator], diameter: float, ratio: float) -> np.ndarray:
    """The parameter vector with every orifice ``diameter`` [m] and every ``V2 = ratio * V1r``."""
    changes: dict[str, float] = {}
    for k, iso in enumerate(isolators):
        changes[f"isolators[{k}].orifice.diameter"] = diameter
        changes[f"isolators[{k}].damping_volume"] = ratio * iso.volume
    return sim.parameter_vector(changes)


def _linear_figures(scenario: Scenario, p: np.ndarray, reference_hz: float) -> dict[str, float]:
    """Heave peak and frequency, rocking peak (worst of rx, ry) and frequency, worst x, y, z transmissibility
    at ``reference_hz``, slowest decay rate [1/s] (air-mass integrators left out)."""
    lin = linearise(scenario, parameters=p)
    response = transmissibility(lin)
    heave = response.peak("z")
    rocking = max((response.peak(a) for a in ("rx", "ry")), key=lambda v: v[0])
    at = lin.frequency_response(np.array([reference_hz]), [f"ground:{a}" for a in _TRANSLATIONS], list(_TRANSLATIONS))
    eig = lin.eigenvalues
    eig = eig[np.abs(eig) > 1e-9 * max(1.0, float(np.abs(eig).max()))]
    return {"heave": heave[0], "heave_hz": heave[1], "rocking": rocking[0], "rocking_hz": rocking[1],
            "at_ref": float(np.max(np.abs(np.diag(at[0])))), "decay": float(-np.max(eig.real))}


def _optimum(sim: Simulator, isolators: Sequence[PneumaticIsolator], d: np.ndarray, heave: np.ndarray,
             ratio: float) -> Optimum:
    """The diameter minimising the heave peak at one volume ratio: the grid's best, refined between its
    neighbours (or up to :data:`EDGE_STRETCH` beyond the grid's end)."""
    if not np.any(np.isfinite(heave)):
        return Optimum(ratio, math.nan, math.nan, math.nan, math.nan, False)
    i = int(np.nanargmin(heave))
    lo = d[i - 1] if i > 0 else d[0] / EDGE_STRETCH
    hi = d[i + 1] if i < d.size - 1 else d[-1] * EDGE_STRETCH

    def peak(log_d: float) -> float:
        try:
            return heave_peak(sim.scenario, _design(sim, isolators, 10**log_d, ratio))[0]
        except UnstableTableError:
            return math.inf

    res = minimize_scalar(peak, bounds=(math.log10(lo), math.log10(hi)), method="bounded",
                          options={"xatol": 1e-7})
    best, value = float(10**res.x), float(res.fun)
    if value > heave[i]:  # the refinement never does worse than the grid
        best, value = float(d[i]), float(heave[i])
    at_edge = (i == 0 and best < d[0] * (1 + 1e-6)) or (i == d.size - 1 and best > d[-1] * (1 - 1e-6))
    near_bound = min(abs(math.log10(best / lo)), abs(math.log10(best / hi))) < 1e-5
    beyond = (i == 0 and near_bound and best < d[0]) or (i == d.size - 1 and near_bound and best > d[-1])
    hz = heave_peak(sim.scenario, _design(sim, isolators, best, ratio))[1]
    tau = relaxation_time_of(sim.scenario, best, ratio)
    return Optimum(ratio, best, value, hz, tau, bool(at_edge or beyond))


def _run_designs(scenario: Scenario, duration: float, designs: list[tuple[Transients, tuple[int, int], np.ndarray]],
                 say: Callable[[str], None], workers: int | None) -> None:
    """Run each design for ``duration`` [s]: ``(into, (i, j), p)``, its figures into ``into`` at ``(i, j)``.

    The designs are one :func:`isolator.sweep.sweep`, zipped ``set`` columns: every isolator's orifice
    diameter [m] and damping-chamber volume [m^3], the values of the parameter vectors ``p`` (which
    differ from the scenario's in those entries only). Each row is :meth:`Simulator.run` of its design: the
    contract's settling time, the settling about the leveling table, the leveling time, whether the supply ran
    out, the band, and with ``[[windows]]`` the window settling and moves per hour.
    """
    timed = replace(scenario, simulation=replace(scenario.simulation, duration=duration))
    names = [n for n in ParameterLayout.of(scenario).names if n.endswith((".orifice.diameter", ".damping_volume"))]
    at = [ParameterLayout.of(scenario).names.index(n) for n in names]
    values = np.array([p for _, _, p in designs])[:, at]
    rows = sweep(timed, set={n: [float(v) for v in values[:, k]] for k, n in enumerate(names)}, zip=True,
                 workers=workers).table()
    valves = any(g.valve is not None for g in scenario.leveling)
    windows = bool(scenario.windows)
    for r, (into, ij, _) in enumerate(designs):
        if rows["status"][r] not in ("ok", "unsettled"):  # unsettled: the run's figures are there
            into.record_failure(ij, duration, str(rows["reason"][r]))
            continue
        level = _known(rows["leveling_time"][r])
        into.record(ij, duration, _known(rows["settling_time_max"][r]), _known(rows["dynamic_settling_time_max"][r]),
                    {"groups": level} if valves else {}, bool(rows["supply_exhausted"][r]),
                    tuple(float(rows[f"band:{s}"][r]) for s in SIGNALS),
                    _known(rows["window_settling_time_max"][r]) if windows else None,
                    _known(rows["moves_per_hour"][r]) if windows else None)
    say(f"  runs: {len(designs)} designs, {int(np.sum(~np.isin(rows['status'], ('ok', 'unsettled'))))} without a "
        "run's figures")


def _known(value: float) -> float | None:
    return None if math.isnan(value) else float(value)


check_public(globals())
