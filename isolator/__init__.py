"""Pneumatic vibration-isolation tables carrying moving stages.

The public API: read a scenario, simulate its carriage transients with the
exact or the paper's model, and read peaks and 5 % settling times; linearise
the parked table for its modes, transmissibility, compliance, stability margin
and vibration-criteria class.

>>> from isolator import load_scenario, simulate, linearise, modes
>>> response = simulate(load_scenario("paper-table-3-2"))
>>> round(response.settling_time_max, 2)                    # s after the carriages stop
2.31
>>> modes(linearise(load_scenario())).frequencies_hz.round(2).tolist()   # Hz
[3.14, 3.36, 3.45, 5.83, 5.9, 6.3]
"""

from __future__ import annotations

from isolator.analysis.budget import ErrorBudget, error_budget
from isolator.analysis.linear import LinearModel, linearise
from isolator.analysis.modes import Modes, modes, modes_over_travel
from isolator.analysis.pneumatic import EquivalentSpringDamper, equivalent_spring_damper
from isolator.analysis.stability import StabilityReport, stability
from isolator.analysis.transmissibility import FrequencyResponse, compliance, transmissibility
from isolator.analysis.vibration import VC_CLASSES, VibrationCriteria, vibration_criteria
from isolator.calibration import CalibrationResult, calibrate
from isolator.errors import (
    IsolatorError,
    OptimisationError,
    ParameterError,
    ScenarioError,
    SimulationError,
    UnstableClosedLoopError,
    UnstableTableError,
)
from isolator.model.cache import get_model
from isolator.model.equilibrium import Equilibrium, RockingStiffness
from isolator.model.parameters import ParameterLayout
from isolator.model.signals import table_signals
from isolator.model.variants import EXACT, MODEL_KINDS, PAPER, Model, ModelVariant, build_model
from isolator.plates import PlateModes, plate_modes, plot_mode_shapes
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import (
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
from isolator.scenario.pneumatic import Air, Capillary, LevelingGroup, PneumaticIsolator, Valve
from isolator.scenario.profile_shapes import samples, scurve, segments, shaped, trapezoid
from isolator.scenario.profiles import PiecewisePolynomialProfile, Profile, SineProfile
from isolator.scenario.reader import bundled_scenarios, load_scenario, scenario_from_dict
from isolator.scenario.tables import load_spectrum
from isolator.simulation.band import Band
from isolator.simulation.batch import BatchResult
from isolator.simulation.leveling import PneumaticResult
from isolator.simulation.response import Response
from isolator.simulation.sequence import run_sequence
from isolator.simulation.sequence_result import SequenceResult, StepResult
from isolator.simulation.settling import SettlingResult, settling_time
from isolator.simulation.simulator import Simulator
from isolator.simulation.single_run import simulate
from isolator.sweep import SweepResult

__all__ = [
    "EXACT",
    "MODEL_KINDS",
    "PAPER",
    "SIGNALS",
    "VC_CLASSES",
    "Actuator",
    "Air",
    "Band",
    "BatchResult",
    "CalibrationResult",
    "Capillary",
    "Carriage",
    "Equilibrium",
    "EquivalentSpringDamper",
    "ErrorBudget",
    "FloorSpectrum",
    "FrequencyResponse",
    "Ground",
    "Isolator",
    "IsolatorError",
    "LevelingGroup",
    "LinearModel",
    "Model",
    "ModelVariant",
    "Modes",
    "MotionLimits",
    "OptimisationError",
    "ParameterError",
    "ParameterLayout",
    "PiecewisePolynomialProfile",
    "PlateModes",
    "PneumaticIsolator",
    "PneumaticResult",
    "Point",
    "Profile",
    "Response",
    "RockingStiffness",
    "Scenario",
    "ScenarioError",
    "SequenceResult",
    "Settling",
    "SettlingResult",
    "SimulationError",
    "SimulationSettings",
    "Simulator",
    "SineProfile",
    "StabilityReport",
    "StepResult",
    "SweepResult",
    "Table",
    "UnstableClosedLoopError",
    "UnstableTableError",
    "Valve",
    "VibrationCriteria",
    "build_model",
    "bundled_scenarios",
    "calibrate",
    "compliance",
    "equivalent_spring_damper",
    "error_budget",
    "get_model",
    "linearise",
    "load_scenario",
    "load_spectrum",
    "modes",
    "modes_over_travel",
    "plate_modes",
    "plot_mode_shapes",
    "run_sequence",
    "samples",
    "scenario_from_dict",
    "scurve",
    "segments",
    "settling_time",
    "shaped",
    "simulate",
    "stability",
    "table_signals",
    "transmissibility",
    "trapezoid",
    "vibration_criteria",
]

__version__ = "0.1.0"

check_public(globals(), foreign=True)  # what the modules defining them do not check (the sweep's result)


def __getattr__(name: str) -> object:
    """Names that left the public API, for one release with a DeprecationWarning (``static_equilibrium``)."""
    from isolator.model.deprecated import deprecated

    return deprecated(name)
