"""Feedback controllers for the active table: state feedback to prototype, output feedback to export.

**State feedback on ideal sensors** (python-control, continuous designs run at a sample rate): the
measurements are the 12 states of :mod:`isolator.analysis.linear` (``x, y, z`` [m], ``rx, ry, rz`` [rad],
``vx .. wz`` [m/s, rad/s]; world axes, from the reference the controller regulates to), the outputs one
commanded force per actuator [N] (``actuator:<name>``). Modules: :mod:`.designs` (:func:`skyhook`,
:func:`pid`, :func:`lead`, :func:`decentralised`; the :class:`Controller` they return),
:mod:`.state_designs` (:func:`lqr`, :func:`hinf`, regulating about the carriages' quasi-static path),
:mod:`.loops` (:func:`closed_loop` with the actuators' lag; :func:`check_stability` continuous and sampled)
and :mod:`.laws` (:func:`feedback_law`: the controller as the simulation runs it).

**Output feedback from the scenario's** ``[[sensors]]`` (what ``isolator controller`` designs and exports):
:mod:`.sensor_plant` (:func:`sensor_plant`: commands to sensors with the actuators' lag, sampled with an
optional delay), :mod:`.output_designs` (:func:`skyhook_design` from collocated geophones,
:func:`lqg_design`), :mod:`.hinf_output` (:func:`hinf_design`), :mod:`.output_feedback`
(:func:`design_controller`: design points, gain scheduling over the travel, the sample-rate check),
:mod:`.robustness` (:func:`check_robustness` over the travel and the isolators' uncertainty, on a bending top
with its elastic modes), :mod:`.rolloff` (:func:`rigid_top`: the bending top's rigid-body model the designs are made on;
:func:`roll_off`: a design unstable or short of margin on the bending top's full plant low-passed above the
isolation band) and
:mod:`.export` (:func:`write_c`: the :class:`DiscreteController` as C99; :func:`from_statespace`
discretises any python-control design into one) and :mod:`.fmu` (:func:`write_controller_fmu`: the same
C as an FMI 2.0 Co-Simulation FMU).

The designs ignore saturation; the checks and the simulation include it. No anti-windup: an integrator
keeps integrating while its actuator saturates.
"""

from __future__ import annotations

from .designs import MEASUREMENTS, SAMPLE_RATE, Controller, decentralised, lead, pid, skyhook
from .export import DiscreteController, ScheduleEntry, from_statespace, write_c
from .fmu import write_controller_fmu
from .hinf_output import hinf_design
from .laws import DiscreteLaw, feedback_law
from .loop_margins import LoopMargins
from .loops import REFERENCE_INPUTS, ClosedLoop, LoopStability, check_stability, closed_loop
from .output_designs import DiscreteDesign, lqg_design, skyhook_design
from .output_feedback import METHODS, design_controller, design_positions
from .robustness import RobustnessCase, RobustnessReport, check_robustness
from .rolloff import rigid_top, roll_off
from .sensor_plant import SensorPlant, loop_matrix, sensor_plant
from .state_designs import hinf, lqr
from .uncertainty import Uncertainty, parse_uncertainty, uncertainty_from_calibration

__all__ = [
    "MEASUREMENTS",
    "METHODS",
    "REFERENCE_INPUTS",
    "SAMPLE_RATE",
    "ClosedLoop",
    "Controller",
    "DiscreteController",
    "DiscreteDesign",
    "DiscreteLaw",
    "LoopMargins",
    "LoopStability",
    "RobustnessCase",
    "RobustnessReport",
    "ScheduleEntry",
    "SensorPlant",
    "Uncertainty",
    "check_robustness",
    "check_stability",
    "closed_loop",
    "decentralised",
    "design_controller",
    "design_positions",
    "feedback_law",
    "from_statespace",
    "hinf",
    "hinf_design",
    "lead",
    "loop_matrix",
    "lqg_design",
    "lqr",
    "parse_uncertainty",
    "pid",
    "rigid_top",
    "roll_off",
    "sensor_plant",
    "skyhook",
    "skyhook_design",
    "uncertainty_from_calibration",
    "write_c",
    "write_controller_fmu",
]
