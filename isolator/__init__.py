"""Pneumatic vibration-isolation tables carrying moving stages.

The public API: read a scenario, simulate its carriage transients with the
exact or the paper's model, and read peaks and 5 % settling times.

>>> from isolator import load_scenario, simulate
>>> response = simulate(load_scenario("paper-table-3-2"))   # doctest: +SKIP
>>> response.settling_time_max                              # doctest: +SKIP
"""

from __future__ import annotations

from .equilibrium import Equilibrium, static_equilibrium
from .errors import IsolatorError, ScenarioError, SimulationError, UnstableTableError
from .loading import bundled_scenarios, load_scenario, scenario_from_dict
from .model import MODEL_KINDS, Model, ParameterLayout, build_model
from .profiles import PiecewisePolynomialProfile, Profile, SineProfile, samples, scurve, trapezoid
from .response import Response
from .scenario import (
    SIGNALS,
    Actuator,
    Carriage,
    Isolator,
    Scenario,
    Settling,
    SimulationSettings,
    Table,
)
from .settling import SettlingResult, settling_time
from .simulation import BatchResult, Simulator, get_model, simulate, table_signals

__all__ = [
    "MODEL_KINDS",
    "SIGNALS",
    "Actuator",
    "BatchResult",
    "Carriage",
    "Equilibrium",
    "Isolator",
    "IsolatorError",
    "Model",
    "ParameterLayout",
    "PiecewisePolynomialProfile",
    "Profile",
    "Response",
    "Scenario",
    "ScenarioError",
    "Settling",
    "SettlingResult",
    "SimulationError",
    "SimulationSettings",
    "Simulator",
    "SineProfile",
    "Table",
    "UnstableTableError",
    "build_model",
    "bundled_scenarios",
    "get_model",
    "load_scenario",
    "samples",
    "scenario_from_dict",
    "scurve",
    "settling_time",
    "simulate",
    "static_equilibrium",
    "table_signals",
    "trapezoid",
]

__version__ = "0.1.0"
