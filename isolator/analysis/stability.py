"""Will the table stand? The rocking-stiffness margin over the carriages' travel, before any simulation."""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np

from isolator.errors import UnstableTableError
from isolator.model.cache import get_model
from isolator.model.equilibrium import RockingStiffness, rocking_stiffness, static_equilibrium
from isolator.model.parameters import ParameterLayout
from isolator.scenario.definitions import Scenario

__all__ = ["StabilityReport", "stability"]


@dataclass(frozen=True)
class StabilityReport:
    """Rocking stiffness at rest configurations spanning the carriages' travel.

    Attributes
    ----------
    positions : ndarray (n_configurations, n_carriages)
        Carriage coordinates checked [m]: the start, the end, and every
        combination of each carriage's stroke limits and mid-point.
    rocking : tuple of RockingStiffness
        One per configuration.
    """

    positions: np.ndarray
    rocking: tuple[RockingStiffness, ...]

    @property
    def worst(self) -> int:
        """Index of the configuration with the smallest margin."""
        return int(np.argmin([r.margin for r in self.rocking]))

    @property
    def margin(self) -> float:
        """Smallest rocking stiffness over the configurations [N m/rad]."""
        return self.rocking[self.worst].margin

    @property
    def relative_margin(self) -> float:
        """That margin as a fraction of the isolators' own rocking stiffness."""
        return self.rocking[self.worst].relative_margin

    @property
    def stable(self) -> bool:
        return self.margin > 0.0

    def describe(self) -> str:
        """One line: stable or not, the margin, where."""
        r = self.rocking[self.worst]
        where = ", ".join(f"{q:.4g}" for q in self.positions[self.worst]) or "no carriages"
        verdict = "stable" if self.stable else "UNSTABLE: the table would tip"
        return f"{verdict}; smallest {r.describe()}, with the carriages at [{where}] m"

    def to_dict(self) -> dict[str, Any]:
        r = self.rocking[self.worst]
        return {
            "stable": self.stable,
            "margin": self.margin,
            "relative_margin": self.relative_margin,
            "axis": r.weakest_axis,
            "isolator_rocking_stiffness": float(r.elastic[0]),
            "positions": [float(q) for q in self.positions[self.worst]],
        }


def stability(scenario: Scenario) -> StabilityReport:
    """Check that the table can stand wherever its carriages go.

    Parameters
    ----------
    scenario : Scenario

    Returns
    -------
    StabilityReport
        Never raises for an unstable table: it reports the negative margin.
    """
    layout = ParameterLayout.of(scenario)
    model = get_model(layout, "exact")
    p = layout.pack(scenario)
    t_end = scenario.simulation.duration
    levels = []
    for carriage in scenario.carriages:
        lo, hi = carriage.profile.position_range(t_end)
        levels.append(sorted({lo, 0.5 * (lo + hi), hi}))
    configs = [scenario.initial_positions()]
    finals = scenario.final_positions()
    if finals is not None:
        configs.append(finals)
    configs += [np.array(combo, dtype=float) for combo in itertools.product(*levels)] if levels else []
    rocking = []
    for q in configs:
        try:
            pose = static_equilibrium(model, p, q, check=False).pose
        except UnstableTableError:  # no equilibrium near upright: judge the upright pose
            pose = np.zeros(6)
        rocking.append(rocking_stiffness(model, p, q, pose))
    return StabilityReport(np.array(configs).reshape(len(configs), -1), tuple(rocking))
