"""Baseline moves for step-and-settle sequences: input-shaped S-curves and ruckig's time-optimal moves.

Each is a move design for :func:`isolator.simulation.sequence.run_sequence` (``move=``): a function of the
step, the carriage, where it is and where it goes, and the step's limits, returning the carriage's profile
in the step's local time.

* :func:`shaped_moves`: the step's S-curve at its limits convolved with a ZV, ZVD or EI shaper tuned to the
  table mode the carriage's acceleration excites most with the carriages parked at the step's targets
  (:func:`controllers.profiles.input_shaping.dominant_modes`, cached per configuration);
* :func:`time_optimal_moves`: ruckig's time-optimal jerk-limited move within the step's limits (for a
  rest-to-rest move with symmetric limits it is the seven-segment S-curve; the two agree to rounding, a
  check of both).
"""

from __future__ import annotations

from dataclasses import replace
from functools import lru_cache

from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import MotionLimits, Scenario
from isolator.scenario.profile_shapes import scurve, shaped
from isolator.scenario.profiles import Profile
from isolator.scenario.sequence import held
from isolator.simulation.sequence import MoveDesign

from .input_shaping import SHAPERS, ExcitedMode, dominant_modes, shaper
from .time_optimal import time_optimal_profile

__all__ = ["dominant_mode", "dominant_modes_at", "shaped_moves", "time_optimal_moves"]


def shaped_moves(scenario: Scenario, kind: str = "zvd") -> MoveDesign:
    """Each step's S-curve shaped by a ``kind`` ("zv", "zvd", "ei") shaper tuned where the step ends.

    Raises
    ------
    ScenarioError
        The scenario has no ``[sequence]``.
    ParameterError
        ``kind`` is unknown.
    """
    sequence = scenario.sequence
    if sequence is None:
        raise ScenarioError("sequence: shaped moves are designed for a [sequence]")
    if kind not in SHAPERS:
        raise ParameterError(f"kind: must be one of {', '.join(SHAPERS)}, got {kind!r}")
    names = [c.name for c in scenario.carriages]
    configurations = sequence.configurations(names)

    def train(carriage: int, parked: tuple[float, ...]) -> tuple[tuple[float, ...], tuple[float, ...]]:
        mode = dominant_mode(scenario, carriage, parked)
        s = shaper(kind, mode.frequency, mode.damping)
        return tuple(s.amplitudes), tuple(s.times)

    def design(step: int, name: str, q0: float, q1: float, limits: MotionLimits) -> Profile:
        if q1 == q0:
            return held(q0)
        move = scurve(q0, q1 - q0, *_given(limits))
        amplitudes, times = train(names.index(name), tuple(map(float, configurations[step + 1])))
        return shaped(move, list(amplitudes), list(times), kind=f"{kind}-shaped")

    return design


def dominant_mode(scenario: Scenario, carriage: int, parked: tuple[float, ...]) -> ExcitedMode:
    """The table mode carriage ``carriage``'s acceleration excites most with the carriages parked at
    ``parked`` [m] (:func:`dominant_modes_at`)."""
    return dominant_modes_at(scenario, carriage, parked)[0]


def dominant_modes_at(scenario: Scenario, carriage: int, parked: tuple[float, ...]) -> list[ExcitedMode]:
    """The table's modes by how much carriage ``carriage``'s acceleration excites them with the carriages
    parked at ``parked`` [m] (:func:`~controllers.profiles.input_shaping.dominant_modes`; cached per
    scenario and configuration)."""
    return list(_dominant(scenario, carriage, tuple(map(float, parked))))


@lru_cache(maxsize=64)
def _dominant(scenario: Scenario, carriage: int, parked: tuple[float, ...]) -> tuple[ExcitedMode, ...]:
    at_rest = replace(scenario, carriages=tuple(replace(c, profile=held(q))
                                                for c, q in zip(scenario.carriages, parked, strict=True)))
    return tuple(dominant_modes(at_rest, carriage))


def time_optimal_moves() -> MoveDesign:
    """Ruckig's time-optimal move of each step within its limits."""

    def design(step: int, name: str, q0: float, q1: float, limits: MotionLimits) -> Profile:
        if q1 == q0:
            return held(q0)
        return time_optimal_profile(q0, q1 - q0, 0.0, *_given(limits))

    return design



def _given(limits: MotionLimits) -> tuple[float, float, float]:
    """A step's limits (run_sequence passes all three: a sequence's carriages have full limits)."""
    return float(limits.velocity or 0.0), float(limits.acceleration or 0.0), float(limits.jerk or 0.0)


check_public(globals())
