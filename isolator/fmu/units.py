"""The SI units of the FMUs' Real variables: each unit's base-unit exponents (``UnitDefinitions`` of
``modelDescription.xml``) and the unit of each parameter field, model state and sensor reading.

Unit names follow the Modelica convention FMI tools read (``m/s2``, ``N.m``, ``kg.m2``; ``1``: dimensionless).
"""

from __future__ import annotations

from collections.abc import Iterable

from isolator.scenario.rules import field_of
from isolator.scenario.sensors import Sensor

__all__ = ["BASE_UNITS", "PARAMETER_UNITS", "parameter_unit", "sensor_unit", "state_units", "unit_definitions"]

#: each unit's exponents of the SI base units (FMI 2.0 ``BaseUnit`` attributes kg, m, s, K, rad)
BASE_UNITS: dict[str, dict[str, int]] = {
    "1": {},
    "m": {"m": 1},
    "m2": {"m": 2},
    "m3": {"m": 3},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "rad/s2": {"rad": 1, "s": -2},
    "1/s": {"s": -1},
    "s": {"s": 1},
    "Hz": {"s": -1},
    "kg": {"kg": 1},
    "kg.m2": {"kg": 1, "m": 2},
    "kg/s": {"kg": 1, "s": -1},
    "kg/(s.m)": {"kg": 1, "m": -1, "s": -1},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N/s": {"kg": 1, "m": 1, "s": -3},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "N/m": {"kg": 1, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "Pa": {"kg": 1, "m": -1, "s": -2},
    "Pa/s": {"kg": 1, "m": -1, "s": -3},
    "Pa.s": {"kg": 1, "m": -1, "s": -1},
    "K": {"K": 1},
    "J/(kg.K)": {"m": 2, "s": -2, "K": -1},
}

#: the unit of each parameter field (:func:`isolator.scenario.rules.field_of` of a parameter's name)
PARAMETER_UNITS: dict[str, str] = {
    "gravity": "m/s2",
    "table.mass": "kg",
    "table.inertia": "kg.m2",
    "table.size": "m",
    "carriages.mass": "kg",
    "carriages.axis": "1",
    "carriages.origin": "m",
    "isolators.position": "m",
    "isolators.stiffness": "N/m",
    "isolators.damping": "N.s/m",
    "isolators.area": "m2",
    "isolators.volume": "m3",
    "isolators.damping_volume": "m3",
    "isolators.orifice.diameter": "m",
    "isolators.orifice.length": "m",
    "isolators.horizontal_stiffness": "N/m",
    "isolators.horizontal_damping": "N.s/m",
    "actuators.position": "m",
    "actuators.direction": "1",
    "actuators.max_force": "N",
    "actuators.bandwidth": "Hz",
    "actuators.max_rate": "N/s",
    "points.position": "m",
    "leveling.line.diameter": "m",
    "leveling.line.length": "m",
    "leveling.sensor": "m",
    "leveling.supply": "Pa",
    "leveling.valve.gain": "kg/(s.m)",
    "leveling.valve.deadband": "m",
    "leveling.valve.max_flow": "kg/s",
    "air.atmosphere": "Pa",
    "air.temperature": "K",
    "air.gas_constant": "J/(kg.K)",
    "air.viscosity": "Pa.s",
    "air.polytropic": "1",
}

#: the units of a sensor's reading by its order (displacement, velocity, acceleration)
_SENSOR_UNITS = ("m", "m/s", "m/s2")
#: the exact model's 13 rigid-body states: position, quaternion (w, x, y, z), velocity, body angular velocity
_RIGID_STATES = ("m",) * 3 + ("1",) * 4 + ("m/s",) * 3 + ("rad/s",) * 3
#: a unit's time derivative, for the states' derivatives
_RATE = {"m": "m/s", "1": "1/s", "m/s": "m/s2", "rad/s": "rad/s2", "Pa": "Pa/s", "N": "N/s"}


def parameter_unit(name: str) -> str:
    """The SI unit of a parameter (``isolators[*].stiffness.z`` -> ``N/m``).

    Raises
    ------
    KeyError
        A parameter field without a unit here (a field added to the rules but not to :data:`PARAMETER_UNITS`).
    """
    field = field_of(name.replace("[*]", "[0]"))
    if field is None or field not in PARAMETER_UNITS:
        raise KeyError(f"no unit for the parameter {name!r}")
    return PARAMETER_UNITS[field]


def sensor_unit(sensor: Sensor) -> str:
    """The SI unit of a sensor's reading (m, m/s, m/s2)."""
    return _SENSOR_UNITS[sensor.order]


def state_units(n_model: int, n_lagged: int) -> tuple[list[str], list[str]]:
    """The units of the plant FMU's states (the exact model's ``n_model``: rigid body, then chamber pressures;
    then ``n_lagged`` actuator forces) and of their derivatives."""
    units = [*_RIGID_STATES, *(["Pa"] * (n_model - len(_RIGID_STATES))), *(["N"] * n_lagged)]
    return units, [_RATE[u] for u in units]


def unit_definitions(units: Iterable[str | None]) -> list[tuple[str, dict[str, int]]]:
    """The ``UnitDefinitions`` of the units used (each once, in :data:`BASE_UNITS` order)."""
    used = set(units)
    return [(name, exponents) for name, exponents in BASE_UNITS.items() if name in used]
