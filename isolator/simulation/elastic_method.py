"""How a transient treats a bending top's elastic modes: in the state (``dynamic``: explicit steps that resolve
them, up to kilohertz), or quasi-static (the modes follow their load: :mod:`isolator.model.quasi_static_top`),
which steps at the rate of the table's own motion.

``auto`` (the default) takes the modes quasi-statically for a plain transient when the lowest elastic mode lies
at least :data:`QUASI_STATIC_RATIO` times above the fastest rate of the table's motion (its rigid modes on the
isolators and any sine drive): the terms dropped are then below ``1 / QUASI_STATIC_RATIO^2`` of the modes' motion
(and ``2 zeta / QUASI_STATIC_RATIO`` for their damping). Runs with actuators acting (forces, a feedback law, a
controller) keep the modes dynamic: a loop can pump a mode, which a quasi-static top cannot show.
"""

from __future__ import annotations

import dataclasses
from typing import Protocol

import numpy as np

from isolator.errors import ParameterError
from isolator.model.equilibrium import Equilibrium
from isolator.model.parameters import ParameterLayout
from isolator.model.quasi_static_top import QuasiStaticTop, quasi_static_top, rest_blocks, stage_values
from isolator.numerics.dop853 import StepPlan
from isolator.scenario.definitions import Scenario
from isolator.simulation.stepping import STAGED_BYTES, Method, fastest_rate, keep_newest
from isolator.simulation.time_grid import layout_inputs

__all__ = ["ELASTIC_CHOICES", "MIN_RATIO", "QUASI_STATIC_RATIO", "QuasiStaticRun", "check_elastic",
           "elastic_rates", "quasi_static_wanted"]

#: how the modes may be treated (``Simulator(elastic=...)``, ``isolator simulate --elastic``)
ELASTIC_CHOICES = ("auto", "dynamic", "quasi-static")
#: ``auto``: quasi-static when the lowest elastic mode is at least this many times the table's fastest rate
QUASI_STATIC_RATIO = 10.0
#: ``quasi-static`` asked for: refused below this ratio (the dropped inertia and damping no longer small)
MIN_RATIO = 3.0


def check_elastic(choice: str) -> str:
    """``choice`` if it is one of :data:`ELASTIC_CHOICES`, else a :class:`ParameterError` naming ``elastic``."""
    if choice not in ELASTIC_CHOICES:
        raise ParameterError(f"elastic: must be one of {', '.join(ELASTIC_CHOICES)}, got {choice!r}")
    return choice


def elastic_rates(equilibrium: Equilibrium) -> tuple[float, float]:
    """The fastest rate of the table's rigid motion and the slowest elastic mode's [rad/s] at a rest of the full
    bending model: its eigenvalues by modulus, the first 13 the rigid table's (12 and the quaternion's norm)."""
    moduli = np.sort(np.abs(equilibrium.eigenvalues))
    return float(moduli[12]), float(moduli[13]) if moduli.size > 13 else float("inf")


def quasi_static_wanted(scenario: Scenario, layout: ParameterLayout, choice: str, actuated: bool,
                        start: Equilibrium, end: Equilibrium | None) -> float | None:
    """The fastest rate [rad/s] a quasi-static run must resolve, or None when the run keeps the modes dynamic
    (a rigid top, actuators acting, ``dynamic``, or ``auto`` with the modes too close to the table's motion).

    Raises
    ------
    ParameterError
        ``quasi-static`` asked for with the lowest mode closer than :data:`MIN_RATIO` to the table's motion.
    """
    if layout.flexible is None or actuated or choice == "dynamic":
        return None
    rests = [e for e in (start, end) if e is not None]
    rigid = max(elastic_rates(e)[0] for e in rests)
    lowest = min(elastic_rates(e)[1] for e in rests)
    fastest = fastest_rate(scenario, rigid)
    ratio = lowest / max(fastest, 1e-12)
    if choice == "quasi-static" and ratio < MIN_RATIO:
        raise ParameterError(
            f"elastic: quasi-static modes need the lowest elastic mode ({lowest / (2 * np.pi):.4g} Hz on the "
            f"isolators) at least {MIN_RATIO:g} times above the table's fastest motion ({fastest / (2 * np.pi):.4g} "
            f"Hz); it is {ratio:.3g} times: use elastic='dynamic'")
    if choice == "auto" and ratio < QUASI_STATIC_RATIO:
        return None
    return fastest


class Stepping(Protocol):
    """What a quasi-static run needs of its simulator (:class:`~isolator.simulation.simulator.Simulator`)."""

    scenario: Scenario
    layout: ParameterLayout

    def step_plan(self, key: int, switches: np.ndarray | None = None) -> StepPlan: ...


class QuasiStaticRun:
    """One run's quasi-static top: what :func:`~isolator.simulation.valve_events.dense_run` steps (``model``,
    :meth:`plan_inputs`), from ``start`` (the table's 13 states at the initial rest), and :meth:`expand`, which
    gives the full bending model's states back.

    Parameters
    ----------
    sim : Simulator
    p : ndarray
        The run's parameters.
    start : Equilibrium
        The full model's initial rest.
    values, rests : dict
        What is kept across runs (the simulator's): the stage values per plan and run, and :func:`rest_blocks` per
        run (its parameters and initial rest).
    """

    def __init__(self, sim: Stepping, p: np.ndarray, start: Equilibrium,
                 values: dict[tuple[int, bytes], np.ndarray],
                 rests: dict[bytes, tuple[np.ndarray, np.ndarray, np.ndarray]]) -> None:
        self.scenario, self.layout, self._sim = sim.scenario, sim.layout, sim
        self.model: QuasiStaticTop = quasi_static_top(sim.layout)
        self.p = np.asarray(p, dtype=float)
        self.start = dataclasses.replace(start, state=np.asarray(start.state[:13], dtype=float))
        self._cache, self._key = values, self.p.tobytes() + self.start.state.tobytes()
        if self._key not in rests:
            rests[self._key] = rest_blocks(self.model, self.layout.rest_inputs(start.positions), self.p, start.state)
            keep_newest(rests, None)
        self._rest = rests[self._key]

    def step_plan(self, key: int, switches: np.ndarray | None = None) -> StepPlan:
        """The simulator's plan."""
        return self._sim.step_plan(key, switches)

    def plan_inputs(self, method: Method, p: np.ndarray) -> np.ndarray:
        """The stage values at every stage of ``method``'s plan (kept per plan and parameters)."""
        if method.plan is None:
            raise ValueError("plan_inputs: the method steps RK4 on the sample grid, it has no step plan")
        key = (method.plan_key, self._key)
        if key not in self._cache:
            inputs = layout_inputs(self.scenario, self.layout, *method.plan.stage_times())
            flat = stage_values(self.model, inputs.reshape(-1, inputs.shape[2]), self.p, self._rest)
            self._cache[key] = flat.reshape(*inputs.shape[:2], -1)
            keep_newest(self._cache, STAGED_BYTES // 4)
        return self._cache[key]

    def expand(self, times: np.ndarray, states: np.ndarray) -> np.ndarray:
        """The full model's states (N, 13 + 2 modes) of the top's states (N, 13) at ``times`` (N,) [s]."""
        times = np.asarray(times, dtype=float)
        values = stage_values(self.model, layout_inputs(self.scenario, self.layout, times, times), self.p,
                              self._rest, expansion=True)
        return self.model.expanded(np.asarray(states, dtype=float), values, self.p)[0]
