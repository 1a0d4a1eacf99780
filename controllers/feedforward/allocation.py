"""The allocation: each instant's cancelling wrench spread over the actuators by least squares.

The wrench (:func:`controllers.feedforward.path.path_demand`) is the
carriages' inertial reaction plus the force that moves the table along its
quasi-static path; each instant is allocated on its own, within the
actuators' force limits (bounded least squares where the minimum-norm
solution exceeds one). What remains is the deviation from the quasi-static
path that the table would see with ideal actuators: second order in the
small rotations.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import lsq_linear

from isolator.analysis.linear import linearise
from isolator.errors import ScenarioError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.simulation.actuation import ForceHistory
from isolator.simulation.time_grid import grid_breakpoints

from .path import QuasiStaticPath, path_demand, quasi_static_path

__all__ = ["Feedforward", "feedforward_allocation"]


@dataclass(frozen=True)
class Feedforward:
    """Feedforward actuator forces and what they were computed from.

    Attributes
    ----------
    forces : ForceHistory
        Commanded forces at the knots (samples and both sides of each breakpoint).
    wrench : ndarray (N, 6)
        The wrench asked of the actuators at the knots [N, N m].
    residual : ndarray (N, 6)
        What the allocation could not give (limits, directions) [N, N m].
    path : QuasiStaticPath
        The table's quasi-static path, which the forces leave alone.
    method : str
        ``"allocation"`` or ``"optimal"``.
    info : dict
        How the forces were found (for ``"optimal"``: solver status, iterations,
        knots, variables, time).
    """

    forces: ForceHistory
    wrench: np.ndarray
    residual: np.ndarray
    path: QuasiStaticPath
    method: str = "allocation"
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def max_force(self) -> dict[str, float]:
        """Largest |force| per actuator [N]."""
        return {n: float(np.max(np.abs(f), initial=0.0)) for n, f in zip(self.forces.names, self.forces.forces,
                                                                          strict=True)}


def _knots(scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """Sample times plus both sides of every breakpoint, with a time on the side to evaluate."""
    samples = scenario.simulation.sample_times()
    bps = grid_breakpoints(scenario.simulation, scenario.breakpoints)  # on the simulation's grid
    samples = samples[~np.isin(samples, bps)]
    eps = 1e-9
    times = np.concatenate([samples, bps, bps])
    sides = np.concatenate([samples, bps - eps, bps + eps])
    order = np.lexsort((sides, times))
    return times[order], sides[order]


def feedforward_allocation(scenario: Scenario, limits: bool = True) -> Feedforward:
    """Instantaneous allocation of the cancelling wrench over the actuators.

    Parameters
    ----------
    scenario : Scenario
        With ``[[actuators]]``.
    limits : bool
        Respect each actuator's ``max_force`` (bounded least squares where the
        minimum-norm solution exceeds one); False: the unconstrained solution.

    Returns
    -------
    Feedforward
        The force histories, the wrench asked and what was left (``residual``), the quasi-static path.

    Raises
    ------
    ScenarioError
        No actuators, or actuators that cannot produce a wrench in every direction
        (the allocation then leaves the unreachable part in ``residual``; only
        no actuators at all is an error).

    Examples
    --------
    >>> from isolator import load_scenario
    >>> from controllers.feedforward import compare_feedforward, feedforward_allocation
    >>> scenario = load_scenario("paper-table-3-2-active")
    >>> ff = feedforward_allocation(scenario)
    >>> round(max(ff.max_force.values()))  # N, the largest command of any actuator (they give 500 N)
    56
    >>> comparison = compare_feedforward(scenario, ff)
    >>> {run: round(max(times.values()), 2) for run, times in comparison.settling.items()}  # largest, s
    {'passive': 2.31, 'controlled': 0.0}
    """
    if not scenario.actuators:
        raise ScenarioError("actuators: the scenario has no [[actuators]] for feedforward")
    lin = linearise(scenario)
    path = quasi_static_path(scenario)
    times, sides = _knots(scenario)
    demand = path_demand(scenario, lin, path, times, sides)
    wrench, b = demand.wrench, demand.allocation  # (N, 6), (N, 6, n)
    forces = np.einsum("nij,nj->ni", np.linalg.pinv(b), wrench)
    if limits:
        cap = np.array([a.max_force for a in scenario.actuators])
        for i in np.flatnonzero(np.any(np.abs(forces) > cap, axis=1)):
            forces[i] = lsq_linear(b[i], wrench[i], bounds=(-cap, cap)).x
    residual = wrench - np.einsum("nij,nj->ni", b, forces)
    names = tuple(a.name for a in scenario.actuators)
    return Feedforward(ForceHistory(times, forces.T, names), wrench, residual, path)


check_public(globals())
