"""How a simulator picks a run's integration: DOP853 steps or RK4 on the sample grid, at the rate of the
fastest eigenvalue of its rests, or of the table's own motion when a bending top's modes are quasi-static
(:mod:`isolator.simulation.elastic_method`)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from isolator.model.equilibrium import Equilibrium
from isolator.model.parameters import ParameterLayout
from isolator.numerics.dop853 import StepPlan, step_plan
from isolator.numerics.step_plan import PROBES
from isolator.scenario.definitions import Scenario
from isolator.simulation.elastic_method import quasi_static_wanted
from isolator.simulation.stepping import (
    DENSE_STEP_ANGLE,
    MAX_DENSE_STEP,
    STEP_ANGLE,
    Method,
    check_step_count,
    fastest_rate,
)
from isolator.simulation.time_grid import TimeGrid
from isolator.simulation.valve_events import with_switches

__all__ = ["MethodChoice"]


class MethodChoice:
    """The integration choices of :class:`~isolator.simulation.simulator.Simulator` (its base)."""

    scenario: Scenario
    layout: ParameterLayout
    grid: TimeGrid
    elastic: str
    _longest_interval: float
    _breakpoints: np.ndarray
    _plans: dict[int, StepPlan]

    def substeps_for(self, omega_max: float, grid: TimeGrid | None = None) -> int:
        """RK4 steps per interval of ``grid`` (default the run's) for a fastest eigenvalue ``omega_max`` [rad/s]
        (:func:`fastest_rate`: the actuators' lags cost no step, :func:`~isolator.simulation.actuation.lag_stages`)."""
        omega = fastest_rate(self.scenario, omega_max)
        longest = self._longest_interval if grid is None else float(np.max(np.diff(grid.nodes), initial=0.0))
        return max(1, math.ceil(omega * longest / STEP_ANGLE))

    def method_for(self, omega_max: float, actuated: bool = False) -> Method:
        """The cheaper integration for a fastest eigenvalue ``omega_max`` [rad/s]: DOP853 steps with |lambda| h <=
        ``DENSE_STEP_ANGLE`` between the breakpoints, unless breakpoints are so dense (sampled profiles) that RK4 on
        the sample grid costs fewer right-hand-side evaluations; RK4 whenever the actuators act (``actuated``:
        forces, a feedback law or a controller)."""
        substeps = self.substeps_for(omega_max)
        omega = max(fastest_rate(self.scenario, omega_max), 1e-12)
        check_step_count(omega, float(self.grid.nodes[-1]), DENSE_STEP_ANGLE, self.scenario)
        if actuated:
            return Method(substeps)
        key = max(0, math.ceil(8 * math.log2(MAX_DENSE_STEP * omega / DENSE_STEP_ANGLE)))
        if key not in self._plans:
            self._plans[key] = self.step_plan(key)
        plan = self._plans[key]
        if plan.evaluations >= 4 * substeps * (self.grid.nodes.size - 1):
            return Method(substeps)
        return Method(substeps, plan, key)

    def step_plan(self, key: int, switches: np.ndarray | None = None) -> StepPlan:
        """DOP853 steps of at most ``MAX_DENSE_STEP 2^(-key/8)`` [s] between the breakpoints and ``switches``."""
        return step_plan(self.grid.samples, with_switches(self._breakpoints, switches, float(self.grid.nodes[-1])),
                         MAX_DENSE_STEP * 2.0 ** (-key / 8), end=self.grid.nodes[-1], probes=PROBES)

    def method_of(self, start: Equilibrium, end: Equilibrium | None, actuated: bool = False) -> Method:
        """:meth:`method_for` the rests' fastest eigenvalue, or the table's when a bending top's modes are quasi-static
        (:func:`~isolator.simulation.elastic_method.quasi_static_wanted`)."""
        rate = quasi_static_wanted(self.scenario, self.layout, self.elastic, actuated, start, end)
        if rate is not None and (method := self.method_for(rate)).plan is not None:
            return dataclasses.replace(method, quasi_static=True)
        return self.method_for(max(start.max_frequency, end.max_frequency if end else 0.0), actuated)
