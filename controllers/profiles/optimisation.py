"""Carriage profiles optimised with casadi through the time-varying model: the public entry.

The design variables are each carriage's move parameters (start delay, cruise
speed, acceleration, deceleration, and jerk for an S-curve; see
:mod:`controllers.profiles.move_design`); the stroke is fixed. The exact
model is integrated by RK4 through the move **in phases**
(:mod:`controllers.profiles.transcription`): the carriages' breakpoints,
merged in the order of the starting design, cut the move into phases in which
every carriage is on one polynomial piece, so each phase is smooth and its
length is an expression of the parameters (the steps of a phase stretch with
it). The order is kept (phase lengths >= 0), and each phase's step is capped;
when a cap binds, the problem is rebuilt with more steps and solved again from
the answer (a warm start).

The objective (:mod:`controllers.profiles.objective`) is smooth, in units of
the 5 % band of each signal: the residual vibration after the stop plus a
penalty beyond a margin of the band. ``objective="settling"`` minimises it
(averaged over the model variants) with the move at most
``max_move_time_increase`` longer than the baseline's; ``objective="cycle"``
minimises the move time with it at most ``residual_limit`` on every variant
(:mod:`controllers.profiles.problem`). Single or multiple shooting; IPOPT
(limited-memory Hessian, :mod:`controllers.profiles.solver`), from a start
screened by simulation (:mod:`controllers.profiles.screening`). The true 5 %
settling time is then measured by the simulation.
"""

from __future__ import annotations

import math
import time
from typing import Any

import casadi as ca
import numpy as np

from isolator.errors import OptimisationError, ScenarioError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario

from .export import write_scenario
from .move_design import command_time, move_designs, move_time
from .move_metrics import evaluate_move
from .objective import peak_floor
from .problem import OBJECTIVES, TRANSCRIPTIONS, Problem, ProfileSettings
from .screening import screened, warm_designs, within_move_time
from .solver import SUCCESS, Monitor, ProfileOptimisation, designs_of, ipopt_options, optimisation_result
from .transcription import variant_data

__all__ = [
    "OBJECTIVES",
    "TRANSCRIPTIONS",
    "ProfileOptimisation",
    "ProfileSettings",
    "optimise_profiles",
    "write_scenario",
]


def optimise_profiles(
    scenario: Scenario,
    settings: ProfileSettings | None = None,
    warm_start: ProfileOptimisation | None = None,
    progress: bool = False,
) -> ProfileOptimisation:
    """Optimise the carriages' profiles to cut the settling (or cycle) time.

    Parameters
    ----------
    scenario : Scenario
        Its carriages' trapezoids or S-curves are the baseline and the
        starting design; their ``limits`` bound the design.
    settings : ProfileSettings, optional
        What to optimise and how (objective, transcription, variants, limits); default
        :class:`ProfileSettings`.
    warm_start : ProfileOptimisation, optional
        Start from an earlier answer (its designs, and its solver point when
        the problem has the same shape).
    progress : bool
        Print a line every ten iterations.

    Returns
    -------
    ProfileOptimisation
        The optimised designs and scenario, the baseline's and the optimised move's metrics, the solver's
        status and times.

    Raises
    ------
    ParameterError
        Bad settings.
    ScenarioError
        Carriages that are not trapezoids or S-curves; floor motion.
    OptimisationError
        IPOPT failed. The message gives its status; ``.result`` holds the best
        feasible point it reached (measured by simulation), or None.
    """
    settings = settings or ProfileSettings()
    settings.check()
    if scenario.ground is not None and scenario.ground.motion:
        raise ScenarioError("ground.motion: profile design needs a still floor")
    designs = move_designs(scenario, settings.shape)
    command = command_time(scenario)
    max_move = (1.0 + settings.max_move_time_increase) * move_time(scenario, command)
    baseline = evaluate_move(scenario, "baseline", command)
    if warm_start is not None:
        designs = warm_designs(designs, warm_start.designs)
    designs = within_move_time(designs, command, max_move)
    if warm_start is None and settings.screen:
        designs = screened(scenario, designs, command, max_move, baseline, settings.objective, progress)
    peaks = peak_floor(baseline.peak)
    data = [variant_data(v.apply(scenario)) for v in settings.variants]
    if progress:
        print(f"optimising {len(designs)} carriages' {settings.shape or 'own'} profiles ({settings.objective}, "
              f"{settings.transcription} shooting, {len(data)} model(s))", flush=True)
    build = solve = 0.0
    iterations = rounds = 0
    point: dict[str, Any] | None = dict(warm_start.warm_start) if warm_start is not None else None
    status = "not run"
    value = math.nan
    for _ in range(4):
        rounds += 1
        t0 = time.perf_counter()
        earlier = point["structure"][0] if point is not None and "structure" in point else None
        problem = Problem(scenario, designs, settings, data, peaks, command, max_move, earlier)
        monitor = Monitor(problem, progress, 1e-6)
        warm = point is not None and point.get("structure") == problem.structure
        options = ipopt_options(settings, monitor, warm)
        args = {"x0": problem.x0, "lbx": problem.lbx, "ubx": problem.ubx, "lbg": problem.lbg, "ubg": problem.ubg}
        if warm and point is not None:
            args.update({"x0": point["x"], "lam_x0": point["lam_x"], "lam_g0": point["lam_g"]})
        solver = ca.nlpsol("profiles", "ipopt", problem.nlp, options)
        build += time.perf_counter() - t0
        t0 = time.perf_counter()
        out = solver(**args)
        solve += time.perf_counter() - t0
        stats = solver.stats()
        status = str(stats["return_status"])
        iterations += int(stats.get("iter_count", 0))
        x = np.asarray(out["x"]).ravel()
        point = {"x": x, "lam_x": np.asarray(out["lam_x"]).ravel(), "lam_g": np.asarray(out["lam_g"]).ravel(),
                 "structure": problem.structure}
        if status not in SUCCESS:
            best = monitor.best[1] if monitor.best is not None else None
            kept = None
            if best is not None:
                kept = optimisation_result(scenario, problem, best, baseline, command, settings, status, iterations,
                                           rounds, build, solve, point)
            message = f"profile optimisation failed: IPOPT {status} after {iterations} iterations"
            if kept is not None:
                message += (f"; best feasible point kept: settling {_fmt(kept.optimised.settling_time_max)}, "
                            f"move {kept.optimised.move_time:.3f} s")
            else:
                message += "; no feasible point was reached"
            error = OptimisationError(message)
            error.result = kept  # type: ignore[attr-defined]
            raise error
        if monitor.best is not None and monitor.best[0] < float(out["f"]):
            x = monitor.best[1]  # IPOPT may stop at an acceptable point worse than one it passed
        value = float(problem.residual(x))
        designs = designs_of(problem, x)
        lengths = np.asarray(problem.durations(x[: problem.n_theta])).ravel()
        caps = np.array([ph.steps * cap for ph, cap in zip(problem.phases, problem.caps, strict=True)])
        if np.all(lengths < 0.95 * caps):
            break
        # a phase outgrew its steps: more steps, from the answer (the warm start fits single shooting)
    return optimisation_result(scenario, problem, x, baseline, command, settings, status, iterations, rounds, build,
                               solve, point, value)


def _fmt(value: float | None) -> str:
    return "unavailable" if value is None else f"{value:.3f} s"


check_public(globals())
