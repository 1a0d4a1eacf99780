"""A top that bends: its free-free modes read from a finite-element model's file (CSV or UFF), checked, and
interpolated over its faces (``[table.flexible]`` and ``feet`` in ``docs/scenario-format.md``).

- :mod:`~isolator.scenario.flexible.definitions`: :class:`ModalData` (the kept elastic modes, the faces'
  C1 interpolation) and :class:`FlexibleTop` (``[table.flexible]``);
- :mod:`~isolator.scenario.flexible.modal_file`: :func:`load_modal_data`, a CSV (``csv_modes``) or UFF
  (``uff_modes``, with pyuff) file read and checked;
- :mod:`~isolator.scenario.flexible.rigid_check`: the six rigid modes' mass, mass centre and inertia
  (:class:`RigidCheck`) and their check against ``[table]``;
- :mod:`~isolator.scenario.flexible.faces`: the faces' nodes and interpolants;
- :mod:`~isolator.scenario.flexible.reader`: the scenario's keys (:func:`read_flexible`, :func:`read_feet`) and
  :func:`load_flexible` for scenarios built in Python.
"""

from __future__ import annotations

from isolator.scenario.arguments import check_public
from isolator.scenario.flexible.definitions import FlexibleTop, ModalData
from isolator.scenario.flexible.faces import FACES, TOLERANCE
from isolator.scenario.flexible.modal_file import load_modal_data
from isolator.scenario.flexible.reader import (
           Feet,
           as_feet,
           check_top,
           flexible_values,
           load_flexible,
           read_feet,
           read_flexible,
)
from isolator.scenario.flexible.rigid_check import RIGID_LIMIT, RigidCheck, check_rigid, fit_rigid, rigid_properties

__all__ = ["FACES", "RIGID_LIMIT", "TOLERANCE", "Feet", "FlexibleTop", "ModalData", "RigidCheck", "as_feet",
           "check_rigid", "check_top", "fit_rigid", "flexible_values", "load_flexible", "load_modal_data",
           "read_feet", "read_flexible", "rigid_properties"]

check_public(globals(), ("FlexibleTop", "ModalData", "load_flexible", "load_modal_data"), foreign=True)
