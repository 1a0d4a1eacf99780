"""The leveling valves' switches as step ends: DOP853 steps that end where a valve's flow is not smooth.

A valve's flow ``clip(gain dz(-h), +-max_flow)`` (``docs/scenario-format.md``, "Pneumatic isolators and
leveling") has kinks where the sensor height ``|h|`` crosses the dead band ``b`` and where the demand reaches
``max_flow`` (``|h| = b + max_flow / gain``), and it stops where a spring chamber of the group reaches the supply
(``p = p_atm + supply``) or the atmosphere. A step across such a switch integrates a right-hand side that is not
smooth there: DOP853's order is lost, and on ``paper-table-3-2-pneumatic`` its steps (|lambda| h <= 0.9) strayed
by 7e-4 of the peak of z from a converged run, at each of the nine times a valve opened or closed. So the run is
stepped again with those times among the breakpoints, located on the dense output (bisection on the steps'
polynomials), until the times its steps end on are the switches of its own solution (three or four runs on
the bundled pneumatic tables, each a plain run's cost: 0.022 s became 0.047 s for a 20 s run); each step then
integrates a smooth right-hand side, and every output is within 4e-8 of its peak of a converged run.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, TypeVar

import numpy as np

from isolator.model.equilibrium import Equilibrium
from isolator.model.parameters import ParameterLayout
from isolator.model.quasi_static_top import QuasiStaticTop
from isolator.model.variants import Model
from isolator.numerics.dop853 import DenseStepper
from isolator.numerics.step_plan import StepPlan
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.simulation.leveling import sensor_heights
from isolator.simulation.stepping import Method, dense_stepper, stage_inputs

__all__ = ["MAX_PASSES", "DenseSimulator", "ValveSwitches", "dense_run", "step_on_switches", "with_switches"]

#: most runs of one table's steps until the times they end on are their own solution's switches
MAX_PASSES = 5
#: switch times [s] that moved less than this between passes are found (the kink then sits within this of a
#: step's end: its error, of the order of the distance squared, far below the run's)
SETTLED = 1e-9
#: points per step at which the switch functions are read for a change of sign (then bisected)
READS = 8

Result = TypeVar("Result")


@dataclass(frozen=True)
class ValveSwitches:
    """Where the valves of a table with the parameters ``p`` switch: functions of the state that change sign
    there (each group's ``|h| - b`` and ``|h| - b - max_flow / gain``, its spring chambers' pressures less
    the supply's and the atmosphere's).

    Attributes
    ----------
    scenario : Scenario
    groups : tuple of int
        The leveling groups with a valve.
    levels : ndarray (groups, 2)
        The sensor heights ``|h|`` [m] at which each group's valve opens and saturates.
    chambers : tuple of tuple of int
        Each group's isolators (their spring chambers' pressures are the states ``13 + k``).
    pressures : ndarray (groups, 2)
        The absolute pressures [Pa] at which filling and exhausting stop.
    """

    scenario: Scenario
    groups: tuple[int, ...]
    levels: np.ndarray
    chambers: tuple[tuple[int, ...], ...]
    pressures: np.ndarray

    @classmethod
    def of(cls, scenario: Scenario, layout: ParameterLayout, p: np.ndarray) -> ValveSwitches | None:
        """The switches of ``scenario``'s valves with the parameter vector ``p``; None without a valve."""
        groups = tuple(j for j, g in enumerate(scenario.leveling) if g.valve is not None)
        if not groups or layout.pneumatic is None:
            return None
        value = dict(zip(layout.names, np.asarray(p, dtype=float), strict=True))
        band = np.array([value[f"leveling[{j}].valve.deadband"] for j in groups])
        full = np.array([value[f"leveling[{j}].valve.max_flow"] / value[f"leveling[{j}].valve.gain"]
                         for j in groups])
        atmosphere = value["air.atmosphere"]
        supply = np.array([atmosphere + value[f"leveling[{j}].supply"] for j in groups])
        return cls(scenario, groups, np.column_stack([band, band + full]),
                   tuple(layout.pneumatic.groups[j] for j in groups),
                   np.column_stack([supply, np.full(len(groups), atmosphere)]))

    def values(self, states: np.ndarray) -> np.ndarray:
        """The switch functions at ``states`` (N, n_states): (N, functions), each changing sign at a switch."""
        heights = np.abs(sensor_heights(self.scenario, states)[list(self.groups)]).T  # (N, groups)
        out = [(heights[:, :, None] - self.levels[None]).reshape(states.shape[0], -1)]
        for k, members in enumerate(self.chambers):
            chambers = states[:, [13 + i for i in members]]
            out.append((chambers[:, :, None] - self.pressures[k][None, None, :]).reshape(states.shape[0], -1))
        return np.hstack(out)

    def times(self, plan: StepPlan, polynomials: np.ndarray) -> np.ndarray:
        """The switches of one run [s], sorted: the sign changes of :meth:`values` between :data:`READS` points
        of each step, bisected on the steps' dense output ``polynomials`` (steps, degree + 1, n_states)."""
        count = min(plan.steps, polynomials.shape[0])
        if count == 0:
            return np.zeros(0)
        fractions = np.arange(READS + 1) / READS
        at = (plan.start[:count, None] + plan.length[:count, None] * fractions[None, :]).ravel()
        at = np.append(np.unique(at[:-1]), plan.end)
        g = self.values(DenseStepper.states_at(plan, polynomials, at))
        point, function = np.nonzero(np.sign(g[1:]) * np.sign(g[:-1]) < 0)
        if point.size == 0:
            return np.zeros(0)
        lo, hi = at[point], at[point + 1]
        g_lo = g[point, function]
        for _ in range(60):  # bisection: 2^-60 of a read interval
            mid = 0.5 * (lo + hi)
            g_mid = self.values(DenseStepper.states_at(plan, polynomials, mid))[np.arange(mid.size), function]
            left = np.sign(g_mid) * np.sign(g_lo) <= 0
            hi, lo = np.where(left, mid, hi), np.where(left, lo, mid)
            g_lo = np.where(left, g_lo, g_mid)
        return np.unique(0.5 * (lo + hi))


def with_switches(breakpoints: np.ndarray, times: np.ndarray | None, end: float) -> np.ndarray:
    """``breakpoints`` [s] and the switch ``times`` [s] (None: none) inside the run, but none within
    :data:`SETTLED` of a breakpoint or of another switch (no step of nearly zero length)."""
    kept = np.asarray(breakpoints, dtype=float)
    if times is None:
        return kept
    for t in np.sort(np.asarray(times, dtype=float)):
        if SETTLED < t < end - SETTLED and not np.any(np.abs(kept - t) <= SETTLED):
            kept = np.append(kept, t)
    return np.sort(kept)


def step_on_switches(
    switches: list[ValveSwitches | None], plan: StepPlan, step: Callable[[StepPlan], Result],
    polynomials: Callable[[Result], list[np.ndarray]], replan: Callable[[np.ndarray], StepPlan],
) -> tuple[StepPlan, Result]:
    """Steps that end on the valves' switches: ``step(plan)`` (one run, or runs side by side sharing the plan),
    then again on ``replan(times)`` (the plan with the switches ``times`` [s] among its breakpoints: every
    run's, for runs side by side) until the switches of the result (read from ``polynomials(result)``, one array
    per run, with ``switches`` None for a run without valves) are the times its plan was made with, within
    :data:`SETTLED` (at most :data:`MAX_PASSES` runs). A run whose valves never switch is stepped once."""
    result = step(plan)
    used: np.ndarray | None = None
    for _ in range(MAX_PASSES - 1):
        found = [s.times(plan, poly) for s, poly in zip(switches, polynomials(result), strict=True) if s is not None]
        times = np.unique(np.concatenate([np.zeros(0), *found]))
        if times.size == 0 if used is None else (times.size == used.size and np.all(np.abs(times - used) <= SETTLED)):
            break
        used = times
        plan = replan(times)
        result = step(plan)
    return plan, result


class DenseSimulator(Protocol):
    """What :func:`dense_run` needs of its simulator (:class:`isolator.simulation.simulator.Simulator`)."""

    scenario: Scenario
    layout: ParameterLayout

    @property
    def model(self) -> Model | QuasiStaticTop:
        """What is stepped (a quasi-static top's plans have no valve switches: its tables have no valves)."""

    def plan_inputs(self, method: Method, p: np.ndarray) -> np.ndarray: ...

    def step_plan(self, key: int, switches: np.ndarray | None = None) -> StepPlan: ...


def dense_run(sim: DenseSimulator, method: Method, p: np.ndarray, start: Equilibrium, final: np.ndarray | None
              ) -> tuple[StepPlan, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """``method``'s DOP853 steps of one run from ``start`` (``final``: the signals' target), ending on the valves'
    switches (:func:`step_on_switches`): the plan stepped, and the signals at its slots, the steps' peaks and
    deviations and their dense output (as ``DenseStepper.run_slots`` gives them), then the signals at the output
    samples (6, samples), zero at the start."""
    plan, stepper, switches = method.plan, dense_stepper(sim.model), ValveSwitches.of(sim.scenario, sim.layout, p)
    if plan is None:
        raise ValueError("dense_run: the method steps RK4 on the sample grid, it has no step plan")

    def step(steps: StepPlan) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        inputs = sim.plan_inputs(method, p) if steps is plan or not isinstance(sim.model, Model) else stage_inputs(
            sim.scenario, sim.model, steps, p)
        samples = np.zeros((6, steps.sample_slots.size + 1))
        raw, peaks, deviations, polynomials = stepper.run_slots(start.state, steps, inputs, p, start.state,
                                                                with_states=True, final=final, samples=samples)
        assert polynomials is not None  # with_states
        return raw, peaks, deviations, polynomials, samples
    if switches is None:
        return plan, step(plan)
    return step_on_switches([switches], plan, step, lambda out: [out[3]],
                            lambda times: sim.step_plan(method.plan_key, times))


# dense_run's arguments come from the simulator, checked there (a 12 s run is a couple of ms: no second check)
check_public(globals(), ("ValveSwitches", "step_on_switches", "with_switches"))
