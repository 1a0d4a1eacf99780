"""How the carriages should move so that the table is still when the move ends.

Modules: :mod:`.move_design` (a carriage's move as parameters within its
drive's limits), :mod:`.move_metrics` (a move judged by the true simulation,
on model variants), :mod:`.input_shaping` (ZV, ZVD and EI shapers tuned to
the dominant modes), :mod:`.time_optimal` (ruckig's jerk-limited moves) and
the profile optimisation through the time-varying model: :mod:`.optimisation`
(:func:`optimise_profiles`, the entry), :mod:`.problem` (settings, the NLP),
:mod:`.objective` (the vibration after the stop, in bands),
:mod:`.transcription` (RK4 in phases, single or multiple shooting),
:mod:`.screening` (the start), :mod:`.solver` (IPOPT and the answer) and
:mod:`.export` (the answer as a scenario file).
"""

from __future__ import annotations

from .export import write_scenario_profiles
from .input_shaping import SHAPERS, ExcitedMode, Shaper, dominant_modes, residual_vibration, shaped_scenario, shaper
from .move_design import (
    DEFAULT_JERK_RAMP,
    SHAPES,
    DriveLimits,
    MoveDesign,
    Segment,
    command_time,
    move_designs,
    move_time,
)
from .move_metrics import ROBUSTNESS_VARIANTS, ModelVariant, MoveMetrics, evaluate_move, over_variants, with_moves
from .optimisation import (
    OBJECTIVES,
    TRANSCRIPTIONS,
    ProfileOptimisation,
    ProfileSettings,
    optimise_profiles,
    write_scenario,
)
from .time_optimal import time_optimal_profile, time_optimal_scenario

__all__ = [
    "DEFAULT_JERK_RAMP",
    "OBJECTIVES",
    "ROBUSTNESS_VARIANTS",
    "SHAPERS",
    "SHAPES",
    "TRANSCRIPTIONS",
    "DriveLimits",
    "ExcitedMode",
    "ModelVariant",
    "MoveDesign",
    "MoveMetrics",
    "ProfileOptimisation",
    "ProfileSettings",
    "Segment",
    "Shaper",
    "command_time",
    "dominant_modes",
    "evaluate_move",
    "move_designs",
    "move_time",
    "optimise_profiles",
    "over_variants",
    "residual_vibration",
    "shaped_scenario",
    "shaper",
    "time_optimal_profile",
    "time_optimal_scenario",
    "with_moves",
    "write_scenario",
    "write_scenario_profiles",
]
