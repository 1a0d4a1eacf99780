"""Feedback controllers for the active table, designed on the linearised plant (python-control).

Every controller here maps the table's measured motion to actuator commands:

* measurements: the 12 states of :mod:`isolator.analysis.linear` (``x, y, z`` [m],
  ``rx, ry, rz`` [rad], ``vx .. wz`` [m/s, rad/s]; world axes, from the
  reference the controller regulates to), as ideal inertial sensors give them;
* outputs: one commanded force per actuator [N] (``actuator:<name>``).

Modules: :mod:`.designs` (:func:`skyhook`, :func:`pid`, :func:`lead`,
:func:`lqr`, :func:`hinf`, :func:`decentralised`; the :class:`Controller`
they return), :mod:`.loops` (:func:`closed_loop` on the linear plant with the
actuators' lag, for transmissibility and compliance with control;
:func:`check_stability` continuous and as sampled: Tustin controller around
the plant held by a zero-order hold) and :mod:`.laws` (:func:`feedback_law`:
the controller as the simulation runs it) and :mod:`.export`
(:class:`DiscreteController`: a discrete controller from the scenario's
sensors to its actuators, optionally gain-scheduled over a carriage's
travel, as ``controller.json`` and as C99 code; :func:`from_statespace`
discretises a python-control design into one). The designs ignore the actuators'
lag and saturation; the checks and the simulation include them. No
anti-windup: an integrator keeps integrating while its actuator saturates.
"""

from __future__ import annotations

from .designs import MEASUREMENTS, SAMPLE_RATE, Controller, decentralised, hinf, lead, lqr, pid, skyhook
from .export import DiscreteController, ScheduleEntry, from_statespace, write_c
from .laws import DiscreteLaw, feedback_law
from .loop_margins import LoopMargins
from .loops import REFERENCE_INPUTS, ClosedLoop, LoopStability, check_stability, closed_loop
from .robustness import RobustnessCase, RobustnessReport, check_robustness
from .uncertainty import Uncertainty, parse_uncertainty, uncertainty_from_calibration

__all__ = [
    "MEASUREMENTS",
    "REFERENCE_INPUTS",
    "SAMPLE_RATE",
    "ClosedLoop",
    "Controller",
    "DiscreteController",
    "DiscreteLaw",
    "LoopMargins",
    "LoopStability",
    "RobustnessCase",
    "RobustnessReport",
    "ScheduleEntry",
    "Uncertainty",
    "check_robustness",
    "check_stability",
    "closed_loop",
    "decentralised",
    "feedback_law",
    "from_statespace",
    "hinf",
    "lead",
    "lqr",
    "parse_uncertainty",
    "pid",
    "skyhook",
    "uncertainty_from_calibration",
    "write_c",
]
