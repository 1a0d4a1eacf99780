"""What a batch (:mod:`isolator.simulation.batch`) settles before it steps: what it needs of its simulator,
every run's rests (solved side by side), and whether a method's arrays fit in memory."""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np

from isolator.errors import UnstableTableError
from isolator.model.equilibrium import Equilibrium, static_equilibria
from isolator.model.parameters import ParameterLayout
from isolator.model.variants import Model
from isolator.numerics.step_plan import StepPlan
from isolator.scenario.definitions import Scenario
from isolator.simulation.resources import check_memory
from isolator.simulation.response import Response
from isolator.simulation.settling import Band
from isolator.simulation.stepping import Method
from isolator.simulation.time_grid import TimeGrid

__all__ = ["BatchSimulator", "both_rests", "check_memory_of", "solve_rests"]

class BatchSimulator(Protocol):
    """What a batch needs of its simulator (:class:`isolator.simulation.simulator.Simulator`)."""

    scenario: Scenario
    layout: ParameterLayout
    model: Model
    grid: TimeGrid
    stop_time: float

    def equilibria_of(self, params: np.ndarray) -> tuple[list[Equilibrium], list[Equilibrium | None]]: ...

    def method_for(self, omega_max: float) -> Method: ...

    def plan_inputs(self, method: Method, p: np.ndarray) -> np.ndarray: ...

    def step_plan(self, key: int, switches: np.ndarray | None = None) -> StepPlan: ...

    def grid_inputs(self, substeps: int) -> np.ndarray: ...

    def signals(self, states: np.ndarray, start: Equilibrium | np.ndarray) -> np.ndarray: ...

    def run_method(self, p: np.ndarray, start: Equilibrium, end: Equilibrium | None, method: Method, *,
                   band: Band | None = None) -> Response: ...


def check_memory_of(sim: BatchSimulator, method: Method, lanes: int, share: float) -> None:
    """Refuse runs of ``method`` whose arrays (RK4: the inputs at every stage of the grid, with the profiles'
    temporaries; DOP853: a pack's dense output and slots, and the staged inputs at every step) would need more
    than ``1 / share`` of the memory available (:class:`ParameterError`): workers run side by side."""
    if method.plan is None:
        intervals = sim.grid.nodes.size - 1
        need = 4.0 * intervals * (2 * method.substeps + 1) * sim.layout.input_size * 8
        what = f"RK4 with {method.substeps} steps per interval of the grid"
    else:
        plan = method.plan
        per_step = lanes * (8 * sim.model.n_states + 6 * plan.per_step) + 16 * max(sim.layout.input_size, 48)
        need = 8.0 * plan.steps * per_step
        what = f"DOP853 with {plan.steps:.3g} steps"
    check_memory(share * need, f"{what} (the design's fastest mode), with {share} runs side by side,",
                 "such a design is far stiffer than a real isolator (or its run far too long)")


def solve_rests(
    sim: BatchSimulator, params: np.ndarray, failed: Callable[[int, Exception], None]
) -> tuple[list[Equilibrium | None], list[Equilibrium | None]]:
    """Start and end equilibria of every run, solved side by side; the runs without a stable rest are
    found by halving the block that has one (None, and ``failed(i, error)`` for each)."""
    n = params.shape[0]
    starts: list[Equilibrium | None] = [None] * n
    ends: list[Equilibrium | None] = [None] * n

    def solve(rows: np.ndarray) -> None:
        try:
            first, last = sim.equilibria_of(params[rows])
        except UnstableTableError as exc:
            if rows.size == 1:
                failed(int(rows[0]), UnstableTableError(str(exc)))
                return
            solve(rows[: rows.size // 2])
            solve(rows[rows.size // 2 :])
            return
        for j, i in enumerate(rows):
            starts[i], ends[i] = first[j], last[j]

    solve(np.arange(n))
    return starts, ends


def both_rests(model: Model, params: np.ndarray, first: np.ndarray, last: np.ndarray
               ) -> tuple[list[Equilibrium], list[Equilibrium | None]] | None:
    """Every run's rests with the carriages at ``first`` and at ``last`` [m] in one Newton solve (the same
    numbers as two: each row's iterations are its own); None when a run has none (the caller solves them
    apart then, for the message naming the rest and the run). Spring-damper tables (a pneumatic table's
    final rest keeps the air of its start)."""
    n = params.shape[0]
    try:
        both = static_equilibria(model, np.vstack([params, params]), np.vstack([np.tile(first, (n, 1)),
                                                                               np.tile(last, (n, 1))]))
    except UnstableTableError:
        return None
    return both[:n], list(both[n:])
