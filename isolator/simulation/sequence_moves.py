"""The carriages' moves in one step of a sequence: each named carriage's S-curve at the step's limits
(lowered by the step's own, started after its delay, convolved with its shaper), or a designed move
(``run_sequence(move=...)``), checked to go where the step says."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.definitions import MotionLimits, Scenario
from isolator.scenario.profile_shapes import scurve, shaped
from isolator.scenario.profiles import Profile
from isolator.scenario.sequence import Move, held
from isolator.scenario.shapers import convolved

__all__ = ["MoveDesign", "step_profiles"]

#: a step's move design: (step index, carriage name, q from [m], q to [m], that step's limits) -> a profile in
#: the step's local time (the step starts at 0), at rest at ``q from`` before it and at ``q to`` after its stop
MoveDesign = Callable[[int, str, float, float, MotionLimits], Profile]


def step_profiles(
    scenario: Scenario, index: int, q: np.ndarray, move_design: MoveDesign | None
) -> tuple[tuple[Profile, ...], np.ndarray, float]:
    """The carriages' profiles of step ``index`` from ``q`` [m] (the step's local time), the targets [m],
    and the stop [s]."""
    sequence = scenario.sequence
    assert sequence is not None
    step = sequence.steps[index]
    profiles: list[Profile] = []
    target = q.copy()
    stop = 0.0
    for i, carriage in enumerate(scenario.carriages):
        mv = step.move(carriage.name)
        if mv is None:
            profiles.append(held(q[i]))
            continue
        lim = carriage.limits
        velocity, acceleration, jerk = mv.limits(float(lim.velocity or 0.0), float(lim.acceleration or 0.0),
                                                 float(lim.jerk or 0.0))
        target[i] = mv.target
        if move_design is not None:
            prof = _designed(move_design, index, carriage.name, float(q[i]), mv.target,
                             MotionLimits(velocity, acceleration, jerk))
        else:
            prof = _scurve_move(mv, float(q[i]), velocity, acceleration, jerk)
        profiles.append(prof)
        stop = max(stop, float(prof.stop_time) if prof.breakpoints else 0.0)
    return tuple(profiles), target, stop


def _scurve_move(mv: Move, q: float, velocity: float, acceleration: float, jerk: float) -> Profile:
    """A step's own move from ``q`` [m] in its local time: the S-curve at these limits [m/s, m/s^2, m/s^3]
    starting at the move's ``delay``, convolved with its shapers if it has any; held when already there."""
    if mv.target == q:
        return held(q)
    move = scurve(q, mv.target - q, velocity, acceleration, jerk, t0=mv.delay)
    if not mv.shapers:
        return move
    amplitudes, times = convolved(mv.shapers)
    kind = "+".join(train.kind for train in mv.shapers)
    return shaped(move, amplitudes, times, kind=f"{kind}-shaped")


def _designed(design: MoveDesign, index: int, name: str, q0: float, q1: float, limits: MotionLimits) -> Profile:
    prof = design(index, name, q0, q1, limits)
    where = f"move: step {index}, carriage '{name}'"
    if not isinstance(prof, Profile):
        raise ParameterError(f"{where}: must return a Profile, got {type(prof).__name__}")
    if not math.isfinite(prof.stop_time):
        raise ParameterError(f"{where}: the profile never stops (a sine); a step's move must stop")
    tol = 1e-9 * max(1.0, abs(q0), abs(q1))
    first, last = prof.position(0.0), prof.position(float(prof.stop_time) + 1.0)
    if abs(first - q0) > tol or abs(last - q1) > tol:
        raise ParameterError(f"{where}: the profile goes from {first:.9g} m to {last:.9g} m, not from the carriage's "
                             f"position {q0:.9g} m to the target {q1:.9g} m")
    return prof
