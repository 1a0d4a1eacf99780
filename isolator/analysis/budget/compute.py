"""The error budget of a parked table: random motion at the points from the floor, forces, actuators' and
sensors' noise, passive or through an exported controller (``docs/scenario-format.md``, "Error budget")."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from isolator.analysis.linear import LinearModel, linearise, rest_positions
from isolator.analysis.travel import check_travel
from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.definitions import Scenario

from .grid import integrate_psd, seed_grid
from .loop import SampledController, SourceResponses, closed_loop_poles
from .result import AXES, QUANTITY_UNITS, ErrorBudget
from .sources import BUDGET_POINT, Source, budget_sources, has_random_sources

__all__ = ["DEFAULT_BAND", "budget_band", "error_budget"]

#: the band [Hz] a budget integrates over by default (with a controller, up to just below half its rate)
DEFAULT_BAND = (0.1, 1000.0)
#: how far below half the controller's rate the default band ends
_BELOW_NYQUIST = 0.999
#: the highest frequency [Hz] a band may reach: no model of a table holds far beyond, and beyond it the powers
#: of the frequency that turn displacement into acceleration leave the floating-point range
MAX_FREQUENCY = 1.0e6


def _point_outputs(lin: LinearModel, points: Sequence[str] | None) -> tuple[tuple[str, ...], list[str]]:
    """The points' names and the linear model's outputs for them (``table``: the mass centre's x, y, z)."""
    names = [p.name for p in lin.scenario.points]
    if not names:
        chosen = list(points) if points is not None else [BUDGET_POINT]
        for p in chosen:
            if p != BUDGET_POINT:
                raise ParameterError(f"points: no point named {p!r}; the scenario has no [[points]], so its "
                                     f"budget is at the mass centre, '{BUDGET_POINT}'")
        return (BUDGET_POINT,), ["x", "y", "z"]
    chosen = names if points is None else list(points)
    if not chosen:
        raise ParameterError("points: name at least one point")
    for p in chosen:
        if p not in names:
            raise ParameterError(f"points: no point named {p!r} (have: {', '.join(names)})")
    return tuple(chosen), [f"{p}:{a}" for p in chosen for a in AXES]


def budget_band(band: Sequence[float] | None, controller: SampledController | None) -> tuple[float, float]:
    """The band [Hz]: checked (0 < low < high, finite; with a controller below half its rate) or the default."""
    nyquist = None if controller is None else float(controller.sample_rate) / 2
    if band is None:
        low, high = DEFAULT_BAND
        return (low, high) if nyquist is None else (low, min(high, _BELOW_NYQUIST * nyquist))
    values = list(band)
    if len(values) != 2 or not all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                                   for v in values):
        raise ParameterError(f"band: must be two finite frequencies (low, high) [Hz], got {band!r}")
    low, high = float(values[0]), float(values[1])
    if not 0 < low < high:
        raise ParameterError(f"band: must be 0 < low < high [Hz], got {low:g} to {high:g}")
    if high > MAX_FREQUENCY:
        raise ParameterError(f"band: ends at {high:g} Hz, beyond {MAX_FREQUENCY:g} Hz, where no model of a table "
                             "holds (its modes and sources lie far below)")
    if nyquist is not None and high >= nyquist:
        raise ParameterError(f"band: ends at {high:g} Hz, at or beyond half the controller's sample rate "
                             f"({nyquist:g} Hz), where the budget neglects aliasing; end it below {nyquist:g} Hz")
    return low, high


def error_budget(
    scenario: Scenario | LinearModel,
    controller: SampledController | None = None,
    points: Sequence[str] | None = None,
    quantity: str = "displacement",
    band: Sequence[float] | None = None,
    positions: Mapping[str, float] | Sequence[float] | None = None,
    relative: Sequence[str] = (),
) -> ErrorBudget:
    """The random motion at the points, per source, as a precision engineer's dynamic error budget.

    The output PSD of a point's motion along world axis ``d`` is ``sum over sources |H(f)|^2 S(f)``, each
    source uncorrelated with the others; the RMS values are the roots of its integral over the band, on a
    grid refined until that integral is converged (0.02 %).

    Parameters
    ----------
    scenario : Scenario or LinearModel
        The table; a scenario is linearised with its carriages at their start (or at ``positions``).
    controller : DiscreteController, optional
        An exported controller (``controller.json``) in the loop: the sampled loop in the frequency domain
        (zero-order hold, the controller's discrete response, the actuators' lag and the design's delay;
        aliasing neglected); a scheduled one taken at the carriages' positions. None: the passive table.
    points : sequence of str, optional
        ``[[points]]`` names (default all; a scenario without points has ``table``, its mass centre).
    quantity : {"displacement", "velocity", "acceleration"}
        Of the points' absolute motion [m, m/s, m/s^2].
    band : (float, float), optional
        [Hz], 0 < low < high; default 0.1 Hz to 1 kHz (with a controller, ending just below half its rate).
    positions : mapping or sequence, optional
        Carriage positions [m] by name or one per carriage (a scenario only), within the carriages' travel
        (:meth:`Scenario.travel() <isolator.scenario.definitions.Scenario.travel>`).
    relative : sequence of str
        ``A:B`` pairs of ``[[points]]``: budget also the elastic translation of ``A`` relative to ``B``
        (table axes; on a top that bends, the tool's motion relative to the part; zero on a rigid top).

    Returns
    -------
    ErrorBudget
        Per point, axis and source: the PSD on the refined grid, the RMS and the cumulative RMS.

    Raises
    ------
    ScenarioError
        The scenario has no random source; a source whose RMS over the band, or the motion it makes, is not a
        finite number (naming its key).
    ParameterError
        An unknown point or quantity, a bad band (beyond :data:`MAX_FREQUENCY`), a controller for another
        table, a carriage parked beyond its travel.
    UnstableClosedLoopError
        The sampled loop is unstable.

    Examples
    --------
    >>> from isolator import load_scenario
    >>> from isolator.analysis.budget import error_budget
    >>> budget = error_budget(load_scenario("paper-table-3-2-budget"))
    >>> len(budget.sources), budget.sources[:4]
    (10, ('floor:x', 'floor:y', 'floor:z', 'force:acoustic-z'))
    >>> round(budget.value("probe", "z") * 1e9)   # nm RMS, absolute: the floor's motion below the isolation
    2416
    >>> round(budget.value("probe", "z", "force:acoustic-z") * 1e9, 2)
    9.73
    """
    if quantity not in QUANTITY_UNITS:
        raise ParameterError(f"quantity: must be one of {', '.join(QUANTITY_UNITS)}, got {quantity!r}")
    if isinstance(scenario, LinearModel):
        if positions is not None:
            raise ParameterError("positions: give them to linearise(); a LinearModel is parked already")
        lin = scenario
    elif isinstance(scenario, Scenario):
        if positions is not None:  # parked where the carriages go, not beyond their travel
            check_travel(scenario, rest_positions(scenario, positions))
        lin = linearise(scenario, positions)
    else:
        raise ParameterError(f"scenario: must be a Scenario or a LinearModel, got {type(scenario).__name__}")
    if controller is not None:
        controller.check_names(lin.scenario)
    limits = budget_band(band, controller)
    names, outputs = _point_outputs(lin, points)
    rate = None if controller is None else float(controller.sample_rate)
    if not has_random_sources(lin.scenario, controller is not None):
        raise ScenarioError("the scenario has no random source for a budget: add [ground.spectrum] (a floor "
                            "spectrum or vc = \"VC-C\"), [[disturbances]], an actuator's noise_psd"
                            + (" or a sensor's noise" if controller is not None else
                               " (sensors' noise counts only with --controller)"))
    order = {"displacement": 0, "velocity": 1, "acceleration": 2}[quantity]
    sources = budget_sources(lin, rate)
    pairs, extra, combine = _relative_outputs(lin, relative, len(outputs))
    f, psd = _spectra(lin, sources, outputs + extra, controller, limits, order, combine)
    silent = _silent_sources(sources, f)
    relative_psd = None
    if pairs:
        relative_psd = psd[:, len(outputs):].reshape(f.size, len(pairs), len(AXES), len(sources)).transpose(
            1, 2, 3, 0)
        psd = psd[:, :len(outputs)]
    psd = psd.reshape(f.size, len(names), len(AXES), len(sources)).transpose(1, 2, 3, 0)
    _check_finite(psd, f, names, sources)
    passive = None
    if controller is not None:  # the same table without the loop, to say where the loop makes it worse
        plain = budget_sources(lin)
        passive = np.zeros((len(names), len(AXES)))
        if plain:
            fp, pp = _spectra(lin, plain, outputs, None, limits, order)
            passive = np.sqrt(np.trapezoid(pp.sum(axis=2), fp, axis=0)).reshape(len(names), len(AXES))
    return ErrorBudget(quantity, limits, None if controller is None else str(controller.method), names,
                       tuple(s.name for s in sources), f, psd, np.asarray(lin.positions, dtype=float),
                       passive_rms=passive, silent=silent, relative=pairs,
                       relative_psd=None if relative_psd is None else np.asarray(relative_psd))


def _relative_outputs(lin: LinearModel, relative: Sequence[str], n_outputs: int
                      ) -> tuple[tuple[str, ...], list[str], np.ndarray | None]:
    """The ``A:B`` pairs checked, the outputs they read (``A:ex .. B:ez``; none on a rigid top) and the matrix
    that combines the budget's outputs and those into the budget's rows (differences for the pairs)."""
    if isinstance(relative, str):
        relative = (relative,)
    names = [p.name for p in lin.scenario.points]
    pairs: list[str] = []
    for text in relative:
        a, sep, b = str(text).partition(":")
        if not sep or a not in names or b not in names or a == b:
            known = ", ".join(names) or "none"
            raise ParameterError(f"relative: expected A:B with two different [[points]] names, got {text!r} "
                                 f"(points: {known})")
        pairs.append(f"{a}:{b}")
    if not pairs:
        return (), [], None
    bends = getattr(lin.scenario.table, "flexible", None) is not None  # a rigid top has no elastic outputs
    extra = [f"{p}:e{a}" for pair in pairs for p in pair.split(":") for a in AXES] if bends else []
    rows = n_outputs + 3 * len(pairs)
    combine = np.zeros((rows, n_outputs + len(extra)))
    combine[:n_outputs, :n_outputs] = np.eye(n_outputs)
    if bends:
        for i in range(len(pairs)):
            for j in range(3):
                combine[n_outputs + 3 * i + j, n_outputs + 6 * i + j] = 1.0
                combine[n_outputs + 3 * i + j, n_outputs + 6 * i + 3 + j] = -1.0
    return tuple(pairs), extra, combine


def _spectra(lin: LinearModel, sources: Sequence[Source], outputs: Sequence[str],
             controller: SampledController | None, limits: tuple[float, float], order: int,
             combine: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The grid [Hz] and each output's PSD per source (nf, outputs, sources), refined until converged;
    ``combine`` (rows, outputs): the PSD of these combinations of the outputs' responses instead."""
    poles = lin.eigenvalues if controller is None else np.concatenate(
        [lin.eigenvalues, closed_loop_poles(lin, controller)])
    corners = np.concatenate([np.asarray(s.corners, dtype=float) for s in sources] + [np.zeros(0)])
    responses = SourceResponses(lin, sources, outputs, controller)

    def evaluate(f: np.ndarray) -> np.ndarray:
        h = responses(f)  # (nf, outputs, sources)
        if combine is not None:
            h = np.einsum("ij,fjs->fis", combine, h)
        gain = np.abs(h) ** 2 * (2 * np.pi * f[:, None, None]) ** (2 * order)
        density = np.stack([np.asarray(s.density(f), dtype=float) for s in sources], axis=1)  # (nf, sources)
        return np.asarray(gain * density[:, None, :])

    return integrate_psd(evaluate, seed_grid(limits, poles, corners))


def _silent_sources(sources: Sequence[Source], f: np.ndarray) -> tuple[str, ...]:
    """The sources with nothing inside the band (their density zero on the whole grid ``f`` [Hz]).

    Raises
    ------
    ScenarioError
        A source whose own variance over the band is not a finite number (a PSD of 1e308 N^2/Hz), naming
        its key.
    """
    silent = []
    for s in sources:
        with np.errstate(over="ignore", invalid="ignore"):
            variance = float(np.trapezoid(np.asarray(s.density(f), dtype=float), f))
        if not math.isfinite(variance):
            raise ScenarioError(f"{s.key or s.name}: the source {s.name}'s RMS over the band {f[0]:g} to {f[-1]:g} "
                                "Hz is not a finite number (its power spectral density is too large to be real)")
        if variance == 0.0:
            silent.append(s.name)
    return tuple(silent)


def _check_finite(psd: np.ndarray, f: np.ndarray, points: Sequence[str], sources: Sequence[Source]) -> None:
    """Refuse a budget whose RMS is not a finite number at some point (naming the point, axis and source)."""
    with np.errstate(over="ignore", invalid="ignore"):
        rms = np.trapezoid(psd, f, axis=-1)  # (points, axes, sources)
    bad = np.argwhere(~np.isfinite(rms))
    if bad.size:
        i, j, k = (int(v) for v in bad[0])
        raise ScenarioError(f"{sources[k].key or sources[k].name}: the motion it makes at {points[i]}:{AXES[j]} is "
                            f"not a finite number: the source is too large, or the table too soft, to be real")
