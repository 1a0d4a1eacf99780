"""The scenario's dataclasses check their own numbers when built, by the rules of :mod:`isolator.scenario.rules`
(``SimulationSettings(duration=-1)``: ``SimulationSettings.duration: must be > 0, got -1``)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.arguments import register_validator
from isolator.scenario.definitions import Actuator, Carriage, Isolator, MotionLimits, Point, SimulationSettings, Table
from isolator.scenario.flexible import FlexibleTop
from isolator.scenario.pneumatic import Air, Capillary, PneumaticIsolator, Valve
from isolator.scenario.rules import check_value, rule_for

__all__ = ["register_field_checks"]


def _field_values(prefix: str) -> Callable[[Any], None]:
    """A validator of a scenario dataclass: each numeric field (a vector: each component) by the rule of
    ``prefix.field``, errors naming ``Class.field``."""
    def validate(obj: Any) -> None:
        for item in dataclasses.fields(obj):
            value, name = getattr(obj, item.name), f"{prefix}.{item.name}"
            if value is None or rule_for(name) is None:
                continue
            for component in _flat(value):
                check_value(name, component, f"{type(obj).__name__}.{item.name}", ParameterError)
    return validate


def _flat(value: Any) -> list[Any]:
    """A number, vector or list of vectors (``feet``) as its numbers."""
    if isinstance(value, tuple | list | np.ndarray):
        return [x for item in value for x in _flat(item)]
    return [value]


def register_field_checks() -> None:
    """Have the scenario's dataclasses check their numbers when built (:func:`register_validator`)."""
    for cls, prefix in ((Table, "table"), (SimulationSettings, "simulation"), (Isolator, "isolators"),
                        (Carriage, "carriages"), (Actuator, "actuators"), (Point, "points"),
                        (MotionLimits, "carriages.limits"), (PneumaticIsolator, "isolators"), (Air, "air"),
                        (Valve, "leveling.valve"), (Capillary, "leveling.line"), (FlexibleTop, "table.flexible")):
        register_validator(cls, _field_values(prefix))
