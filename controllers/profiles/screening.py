"""The profile optimisation's start: a warm start's designs, a start within the move-time limit, and
braking phases screened by simulation (the objective has many local minima)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario

from .input_shaping import ExcitedMode, dominant_modes
from .move_design import MoveDesign
from .move_metrics import MoveMetrics, evaluate_move, with_moves

__all__ = ["braking_candidates", "screened", "warm_designs", "within_move_time"]


def warm_designs(designs: tuple[MoveDesign, ...], previous: Sequence[MoveDesign]) -> tuple[MoveDesign, ...]:
    """The designs with an earlier answer's values where carriage and shape match."""
    by_name = {d.name: d for d in previous}
    return tuple(
        d.with_values(by_name[d.name].values) if d.name in by_name and by_name[d.name].shape == d.shape else d
        for d in designs
    )


def within_move_time(designs: tuple[MoveDesign, ...], command: float, max_move: float) -> tuple[MoveDesign, ...]:
    """A starting design that ends within the move-time limit (an S-curve from a trapezoid runs longer).

    Speeds the slow carriages up within their limits, else leaves the design
    for IPOPT to repair. An answer that meets the limit within the solver's
    tolerance (a warm start) is kept as it is."""
    out = []
    for d in designs:
        if d.stop_time() - command > max_move * (1 + 1e-6) + 1e-9:
            lim = d.limits
            jerk = lim.jerk if d.shape == "scurve" else None
            d = replace(d, velocity=lim.velocity, acceleration=lim.acceleration, deceleration=lim.acceleration,
                        jerk=jerk, deceleration_jerk=jerk)
        out.append(d)
    return tuple(out)


def screened(scenario: Scenario, designs: tuple[MoveDesign, ...], command: float, max_move: float,
              baseline: MoveMetrics, objective: str, progress: bool) -> tuple[MoveDesign, ...]:
    """The starting design with each carriage's braking timed to its excited modes' periods, where the
    simulation says that settles (or ends the cycle) sooner; one pass over the carriages."""
    peaks = list(baseline.peak.values())
    best = list(designs)
    best_score = _score(scenario, best, command, objective)
    tried = 0
    for i, d in enumerate(designs):
        modes = dominant_modes(scenario, i, peaks)[:3]
        for candidate in braking_candidates(d, modes, command, max_move):
            trial = [*best[:i], candidate, *best[i + 1:]]
            score = _score(scenario, trial, command, objective)
            tried += 1
            if score < best_score:
                best, best_score = trial, score
    if progress:
        print(f"  screened {tried} braking timings: start from {objective} {best_score[0]:.3f} s", flush=True)
    return tuple(best)


def _score(scenario: Scenario, designs: Sequence[MoveDesign], command: float, objective: str) -> tuple[float, float]:
    """(settling or cycle time, move time) of a design by simulation; unknown settling counts as very long."""
    metrics = evaluate_move(with_moves(scenario, designs), "screen", command)
    settle = math.inf if metrics.settling_time_max is None else metrics.settling_time_max
    return (settle if objective == "settling" else settle + metrics.move_time, metrics.move_time)


def braking_candidates(design: MoveDesign, modes: Sequence[ExcitedMode], command: float,
                        max_move: float) -> list[MoveDesign]:
    """Braking phases whose pulse has spectral zeros at the modes' damped periods.

    A trapezoid's braking is a rectangle of length ``T_d``: zeros at ``k / T_d``.
    An S-curve's is a rectangle of length ``T_j + T_c`` smoothed by one of
    length ``T_j``: zeros at ``k / (T_j + T_c)`` and ``k / T_j``.
    """
    lim = design.limits
    periods = [1.0 / (m.frequency * math.sqrt(1 - m.damping**2)) for m in modes]
    out = []
    for period in periods[:2]:
        for k in (1, 2, 3):
            plateau = k * period
            dec = design.velocity / plateau
            if dec > lim.acceleration:
                continue
            if design.shape == "trapezoid":
                out.append(replace(design, deceleration=dec))
                continue
            for ramp in {*(p for p in periods if p < plateau), plateau / 2}:
                jerk = dec / ramp
                if jerk <= lim.jerk:
                    out.append(replace(design, deceleration=dec, deceleration_jerk=jerk))
    return [c for c in out if c.fits() and c.stop_time() - command <= max_move]


check_public(globals())
