"""The error budget: random motion at the points from the floor, forces, actuators' and sensors' noise,
passive or through an exported controller (``docs/scenario-format.md``, "Error budget: random disturbances
and noise at the points")."""

from isolator.analysis.budget.compute import DEFAULT_BAND, budget_band, error_budget
from isolator.analysis.budget.loop import SampledController
from isolator.analysis.budget.result import AXES, QUANTITY_UNITS, ErrorBudget
from isolator.analysis.budget.sources import (
    BUDGET_POINT,
    Source,
    budget_point_names,
    budget_sources,
    has_random_sources,
)

__all__ = ["AXES", "BUDGET_POINT", "DEFAULT_BAND", "QUANTITY_UNITS", "ErrorBudget", "SampledController", "Source",
           "budget_band", "budget_point_names", "budget_sources", "error_budget", "has_random_sources"]
