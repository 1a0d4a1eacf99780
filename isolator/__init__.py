"""Pneumatic vibration-isolation tables carrying moving stages.

The public API: read a scenario, simulate its carriage transients with the
exact or the paper's model, and read peaks and 5 % settling times; linearise
the parked table for its modes, transmissibility, compliance, stability margin
and vibration-criteria class.

>>> from isolator import load_scenario, simulate, linearise, modes
>>> response = simulate(load_scenario("paper-table-3-2"))   # doctest: +SKIP
>>> response.settling_time_max                              # doctest: +SKIP
>>> modes(linearise(load_scenario())).frequencies_hz        # doctest: +SKIP
"""

from __future__ import annotations

from .batch import BatchResult
from .equilibrium import Equilibrium, RockingStiffness, static_equilibrium
from .errors import (
    IsolatorError,
    OptimisationError,
    ScenarioError,
    SimulationError,
    UnstableClosedLoopError,
    UnstableTableError,
)
from .linear import LinearModel, linearise
from .loading import bundled_scenarios, load_scenario, load_spectrum, scenario_from_dict
from .model import MODEL_KINDS, Model, ParameterLayout, build_model
from .modes import Modes, modes, modes_over_travel
from .profiles import PiecewisePolynomialProfile, Profile, SineProfile, samples, scurve, segments, shaped, trapezoid
from .response import Response
from .scenario import (
    SIGNALS,
    Actuator,
    Carriage,
    FloorSpectrum,
    Ground,
    Isolator,
    MotionLimits,
    Point,
    Scenario,
    Settling,
    SimulationSettings,
    Table,
)
from .settling import SettlingResult, settling_time
from .simulation import Simulator, get_model, simulate, table_signals
from .stability import StabilityReport, stability
from .transmissibility import FrequencyResponse, compliance, transmissibility
from .vibration import VC_CLASSES, VibrationCriteria, vibration_criteria

__all__ = [
    "MODEL_KINDS",
    "SIGNALS",
    "VC_CLASSES",
    "Actuator",
    "BatchResult",
    "Carriage",
    "Equilibrium",
    "FloorSpectrum",
    "FrequencyResponse",
    "Ground",
    "Isolator",
    "IsolatorError",
    "LinearModel",
    "Model",
    "Modes",
    "MotionLimits",
    "OptimisationError",
    "ParameterLayout",
    "PiecewisePolynomialProfile",
    "Point",
    "Profile",
    "Response",
    "RockingStiffness",
    "Scenario",
    "ScenarioError",
    "Settling",
    "SettlingResult",
    "SimulationError",
    "SimulationSettings",
    "Simulator",
    "SineProfile",
    "StabilityReport",
    "Table",
    "UnstableClosedLoopError",
    "UnstableTableError",
    "VibrationCriteria",
    "build_model",
    "bundled_scenarios",
    "compliance",
    "get_model",
    "linearise",
    "load_scenario",
    "load_spectrum",
    "modes",
    "modes_over_travel",
    "samples",
    "scenario_from_dict",
    "scurve",
    "segments",
    "settling_time",
    "shaped",
    "simulate",
    "stability",
    "static_equilibrium",
    "table_signals",
    "transmissibility",
    "trapezoid",
    "vibration_criteria",
]

__version__ = "0.1.0"
