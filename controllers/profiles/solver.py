"""Solving the profile problem with IPOPT: its options, a monitor of its iterations, and the answer
measured by simulation (:class:`ProfileOptimisation`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario

from .move_design import MoveDesign
from .move_metrics import MoveMetrics, evaluate_move, with_moves
from .problem import Problem, ProfileSettings

__all__ = ["SUCCESS", "Monitor", "ProfileOptimisation", "designs_of", "ipopt_options", "optimisation_result"]

#: IPOPT's statuses that count as solved
SUCCESS = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


@dataclass(frozen=True)
class ProfileOptimisation:
    """An optimised move and how it compares with the baseline, by simulation.

    Attributes
    ----------
    designs : tuple of MoveDesign
        The optimised parameters per carriage.
    scenario : Scenario
        The scenario with the optimised profiles.
    baseline, optimised : MoveMetrics
        Measured by the true simulation (nominal model).
    objective, transcription : str
    status : str
        IPOPT's return status.
    iterations : int
        Summed over the rounds.
    rounds : int
        Solves (1, or more when a step cap was raised).
    build_time, solve_time : float
        Wall time [s] building the problems and solving them.
    objective_value : float
        ``R + H`` (mean over the variants) at the answer.
    warm_start : dict
        The solver's last primal and dual point, for :func:`optimise_profiles`'s ``warm_start``.
    """

    designs: tuple[MoveDesign, ...]
    scenario: Scenario
    baseline: MoveMetrics
    optimised: MoveMetrics
    objective: str
    transcription: str
    status: str
    iterations: int
    rounds: int
    build_time: float
    solve_time: float
    objective_value: float
    warm_start: dict[str, Any] = field(repr=False, compare=False)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (``baseline``, ``optimised``, ``designs``, solver facts)."""
        return {
            "objective": self.objective,
            "transcription": self.transcription,
            "baseline": self.baseline.to_dict(),
            "optimised": self.optimised.to_dict(),
            "designs": [
                {"carriage": d.name, "shape": d.shape, **dict(zip(d.names, map(float, d.values), strict=True))}
                for d in self.designs
            ],
            "solver": {"status": self.status, "iterations": self.iterations, "rounds": self.rounds,
                       "build_time": self.build_time, "solve_time": self.solve_time,
                       "objective_value": self.objective_value},
        }


class Monitor(ca.Callback):
    """IPOPT's iterations: progress lines and the best feasible point seen."""

    def __init__(self, problem: Problem, progress: bool, tolerance: float) -> None:
        ca.Callback.__init__(self)
        self.n_x, self.n_g = problem.nlp["x"].shape[0], problem.nlp["g"].shape[0]
        self.lbg, self.ubg = problem.lbg, problem.ubg
        self.lbx, self.ubx = problem.lbx, problem.ubx
        self.progress = progress
        self.tolerance = tolerance
        self.iteration = 0
        self.best: tuple[float, np.ndarray] | None = None
        self.construct("monitor", {})

    def get_n_in(self) -> int:
        return ca.nlpsol_n_out()

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return ca.nlpsol_out(i)

    def get_name_out(self, i: int) -> str:
        return "ret"

    def get_sparsity_in(self, i: int) -> ca.Sparsity:
        name = ca.nlpsol_out(i)
        if name == "f":
            return ca.Sparsity.scalar()
        if name in ("x", "lam_x"):
            return ca.Sparsity.dense(self.n_x)
        if name in ("g", "lam_g"):
            return ca.Sparsity.dense(self.n_g)
        return ca.Sparsity(0, 0)

    def eval(self, arg: Sequence[ca.DM]) -> list[int]:
        self.iteration += 1
        x = np.asarray(arg[0]).ravel()
        f = float(arg[1])
        g = np.asarray(arg[2]).ravel()
        violation = max(float(np.max(self.lbg - g, initial=0.0)), float(np.max(g - self.ubg, initial=0.0)),
                        float(np.max(self.lbx - x, initial=0.0)), float(np.max(x - self.ubx, initial=0.0)))
        if violation <= self.tolerance and (self.best is None or f < self.best[0]):
            self.best = (f, x.copy())
        if self.progress and self.iteration % 10 == 0:
            print(f"  iteration {self.iteration}: objective {f:.4g}, constraint violation {violation:.2g}", flush=True)
        return [0]


def designs_of(problem: Problem, x: np.ndarray) -> tuple[MoveDesign, ...]:
    """The designs at a solver point, held within their bounds (IPOPT may overstep them by its tolerance)."""
    n = problem.n_theta
    theta = np.clip(x[:n], problem.lbx[:n], problem.ubx[:n]) * problem.scales
    out, at = [], 0
    for d in problem.designs:
        out.append(d.with_values(theta[at: at + len(d.names)]))
        at += len(d.names)
    return tuple(out)


def optimisation_result(scenario: Scenario, problem: Problem, x: np.ndarray, baseline: MoveMetrics, command: float,
            settings: ProfileSettings, status: str, iterations: int, rounds: int, build: float, solve: float,
            point: dict[str, Any] | None, value: float | None = None) -> ProfileOptimisation:
    designs = designs_of(problem, x)
    optimised_scenario = with_moves(scenario, designs)
    optimised = evaluate_move(optimised_scenario, "optimised", command)
    return ProfileOptimisation(
        designs=designs, scenario=optimised_scenario, baseline=baseline, optimised=optimised,
        objective=settings.objective, transcription=settings.transcription, status=status,
        iterations=iterations, rounds=rounds, build_time=build, solve_time=solve,
        objective_value=float(problem.residual(x)) if value is None else value,
        warm_start=point or {},
    )



def ipopt_options(settings: ProfileSettings, monitor: Monitor, warm: bool) -> dict[str, Any]:
    """IPOPT's options: limited-memory Hessian, the settings' iterations and tolerance, ``monitor`` called
    at each iteration; with ``warm``, started at an earlier answer itself."""
    options: dict[str, Any] = {
        "ipopt.hessian_approximation": "limited-memory",
        "ipopt.limited_memory_max_history": 30,
        "ipopt.mu_strategy": "adaptive",
        "ipopt.max_iter": settings.max_iterations,
        "ipopt.tol": settings.tolerance,
        "ipopt.acceptable_tol": 1e3 * settings.tolerance,
        "ipopt.acceptable_obj_change_tol": 1e-4,
        "ipopt.acceptable_iter": 5,
        "ipopt.print_level": 0,
        "ipopt.sb": "yes",
        "print_time": False,
        "iteration_callback": monitor,
    }
    if warm:
        # start at the earlier answer itself: IPOPT's default pushes it off its active bounds
        options.update({"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-6,
                        "ipopt.warm_start_bound_push": 1e-9, "ipopt.warm_start_bound_frac": 1e-9,
                        "ipopt.warm_start_slack_bound_push": 1e-9, "ipopt.warm_start_slack_bound_frac": 1e-9,
                        "ipopt.warm_start_mult_bound_push": 1e-9})
    return options


check_public(globals())
