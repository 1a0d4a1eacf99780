"""Will the table stand? The rocking-stiffness margin over the carriages' travel, before any simulation."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from isolator.model.cache import get_model
from isolator.model.equilibrium import RockingStiffness
from isolator.model.parameters import ParameterLayout
from isolator.model.tipping import rocking_over, tipping_verdict, travel_configurations
from isolator.scenario.arguments import check_public
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
        return tipping_verdict(self.positions, self.rocking)[1]

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
        """The one criterion (:func:`isolator.model.tipping.tipping_verdict`) simulations refuse by."""
        return tipping_verdict(self.positions, self.rocking)[0]

    def describe(self) -> str:
        """One line: stable or not, the margin, where (what a refused simulation says too)."""
        return tipping_verdict(self.positions, self.rocking)[2]

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
        The scenario (or a bundled scenario's name, or a TOML file's path).

    Returns
    -------
    StabilityReport
        Never raises for an unstable table: it reports the negative margin.

    Examples
    --------
    >>> from isolator import load_scenario, stability
    >>> report = stability(load_scenario("paper-table-3-2"))
    >>> report.stable
    True
    >>> print(report.describe())  # doctest: +ELLIPSIS
    stable; smallest rocking stiffness about rx = 5.613e+05 N m/rad ...
    """
    layout = ParameterLayout.of(scenario)
    configs = travel_configurations(scenario)
    return StabilityReport(configs, rocking_over(get_model(layout, "exact"), layout.pack(scenario), configs))


check_public(globals(), ("StabilityReport", "stability"))
