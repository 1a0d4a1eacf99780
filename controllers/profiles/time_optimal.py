"""Time-optimal jerk-limited moves from ruckig, the fastest a drive's limits allow.

Each carriage moves alone from rest to rest within its ``limits`` (speed,
acceleration, jerk; see :func:`controllers.profiles.move_design.drive_limits`), starting
when its scenario profile starts. Ruckig returns each move as seven
constant-jerk phases; they become an exact piecewise-cubic profile.
"""

from __future__ import annotations

from isolator.errors import OptimisationError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.profile_shapes import segments
from isolator.scenario.profiles import PiecewisePolynomialProfile

from .move_design import move_designs
from .move_metrics import with_moves

__all__ = ["time_optimal_profile", "time_optimal_scenario"]


def time_optimal_profile(start: float, stroke: float, t0: float, velocity: float, acceleration: float,
                         jerk: float) -> PiecewisePolynomialProfile:
    """Ruckig's time-optimal rest-to-rest move.

    Parameters
    ----------
    start, stroke : float
        [m]
    t0 : float
        Start time [s].
    velocity, acceleration, jerk : float
        Limits [m/s, m/s^2, m/s^3], > 0.

    Returns
    -------
    PiecewisePolynomialProfile
        The move, at rest before ``t0`` and after it arrives.
    """
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    inp = InputParameter(1)
    inp.current_position = [start]
    inp.target_position = [start + stroke]
    inp.max_velocity = [velocity]
    inp.max_acceleration = [acceleration]
    inp.max_jerk = [jerk]
    trajectory = Trajectory(1)
    result = Ruckig(1).calculate(inp, trajectory)
    if result not in (Result.Working, Result.Finished):
        raise OptimisationError(f"limits: ruckig found no move ({result})")
    phase = trajectory.profiles[0][0]
    return segments(start, t0, list(phase.t), list(phase.a[:7]), list(phase.j), kind="time-optimal")


def time_optimal_scenario(scenario: Scenario) -> Scenario:
    """The scenario with every carriage's move replaced by ruckig's time-optimal one within its limits.

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).

    Returns
    -------
    Scenario
        The scenario with each carriage's profile ruckig's time-optimal move (same start, stroke and start
        time).
    """
    profiles = [
        time_optimal_profile(d.start, d.stroke, d.t0, d.limits.velocity, d.limits.acceleration, d.limits.jerk)
        for d in move_designs(scenario)
    ]
    return with_moves(scenario, profiles)


check_public(globals())
