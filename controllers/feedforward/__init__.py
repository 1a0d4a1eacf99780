"""Feedforward cancellation of the carriages' reaction on the table, from the planned motion.

What the actuators hold and what they leave: the carriages' weight moving
across the table tilts it quasi-statically (the static equilibrium follows
the carriages). Holding that tilt would take a standing force after every
move (Table 3.2: about 2,700 N m for the 400 kg stage moving 1.4 m, more
than four 500 N actuators at 1 m can give) and is the job of the isolators'
slow leveling valves. So the feedforward leaves the table on its
**quasi-static path** and cancels everything else: it supplies

* the carriages' inertial reaction, ``sum m_i a_i`` and ``sum m_i d_i x a_i``
  (their accelerations relative to the table, about its mass centre), and
* the small force that moves the table along its quasi-static path,
  ``M z_qs'' + C z_qs'`` (linearised mass and damping at the start),

allocated over the actuators by least squares within their force limits
(``method="allocation"``). What remains is the deviation from the
quasi-static path that the table would see with ideal actuators: second
order in the small rotations.

Modules: :mod:`.wrench` (the reaction and allocation wrenches), :mod:`.path`
(the quasi-static path and the demand along it), :mod:`.allocation` (the
instantaneous allocation), :mod:`.optimal` (command histories optimised
through the time-varying model, with the actuators' lag and limits and a
pneumatic table's chamber pressures; its model along the path in
:mod:`.optimal_stages`), :mod:`.comparison` (passive against controlled runs).
"""

from __future__ import annotations

from .allocation import Feedforward, feedforward_allocation
from .comparison import FeedforwardComparison, compare_feedforward, path_deviation, run_quasi_static, settling_in_band
from .optimal import OptimalSettings, feedforward_optimal
from .path import QS_SPACING, AirDemand, PathDemand, QuasiStaticPath, path_demand, quasi_static_path
from .wrench import allocation_matrix, carriage_inertia_wrench, reaction_wrench

__all__ = [
    "QS_SPACING",
    "AirDemand",
    "Feedforward",
    "FeedforwardComparison",
    "OptimalSettings",
    "PathDemand",
    "QuasiStaticPath",
    "allocation_matrix",
    "carriage_inertia_wrench",
    "compare_feedforward",
    "feedforward_allocation",
    "feedforward_optimal",
    "path_demand",
    "path_deviation",
    "quasi_static_path",
    "reaction_wrench",
    "run_quasi_static",
    "settling_in_band",
]
