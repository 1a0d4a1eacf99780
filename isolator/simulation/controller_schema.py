"""``controller.json`` checked against its schema before a :class:`DiscreteController` is made of it.

A controller folder travels (from a colleague, a vendor, a CI job), so its JSON is read strictly: a JSON
object (a key it does not know is warned about and ignored: the contract lists what it holds at least);
``sample_rate`` a number, ``delay`` a JSON boolean (``"false"`` is no boolean), ``method`` a string,
``settings`` an object, names lists of strings (by the rule for names of :mod:`isolator.scenario.names`);
every matrix a list of rows of JSON numbers (not strings, not booleans), each row as long as the first;
each ``schedule`` entry an object with ``q``, ``A``, ``B``, ``C``, ``D``; ``schedule_carriage`` a whole
number. Shapes and finiteness are then the :class:`DiscreteController`'s own checks. Every problem is one
:class:`ParameterError` naming ``controller.<key>``.

:func:`spectral_radius` and :func:`warn_if_unstable` tell of a controller unstable on its own (``A`` with an
eigenvalue outside the unit circle): allowed (a design may need one), but worth a warning when it comes
from a file.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.names import check_name, escaped

__all__ = ["CONTROLLER_KEYS", "MAX_STATES", "check_controller_data", "check_states", "spectral_radius",
           "warn_if_unstable"]

#: the most states a controller may have, whichever command reads it: each sample costs ``n^2`` operations in a
#: simulation, the budget and the FMU diagonalise ``A`` (``n^3``), the C export writes ``n^2`` numbers; the
#: designs of ``isolator controller`` have tens (a 2,000-state one would run for many minutes, or not fit)
MAX_STATES = 500

#: the keys of ``controller.json`` (docs/scenario-format.md, "exported controllers"); ``robustness`` is the
#: report ``isolator controller`` records (an object, not read)
CONTROLLER_KEYS = ("sample_rate", "sensors", "actuators", "carriages", "method", "delay", "settings", "A", "B",
                   "C", "D", "schedule", "schedule_carriage", "robustness")
_MATRICES = ("A", "B", "C", "D")
_ENTRY_KEYS = ("q", *_MATRICES)


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _numbers(value: object, key: str) -> list[float]:
    """A JSON list of numbers."""
    if not isinstance(value, list) or not all(_is_number(v) for v in value):
        raise ParameterError(f"{key}: must be a list of numbers, got {_kind(value)}")
    return [float(v) for v in value]


def _matrix(value: object, key: str) -> list[list[float]]:
    """A JSON matrix: a list of rows, each a list of numbers as long as the first (an empty list: no rows)."""
    if not isinstance(value, list):
        raise ParameterError(f"{key}: must be a list of rows (lists of numbers), got {_kind(value)}")
    rows = [_numbers(row, f"{key}[{i}]") for i, row in enumerate(value)]
    for i, row in enumerate(rows):
        if len(row) != len(rows[0]):
            raise ParameterError(f"{key}[{i}]: {len(row)} numbers where row 0 has {len(rows[0])}")
    return rows


def _kind(value: object) -> str:
    """What a JSON value is, for a message (never its content beyond a short excerpt)."""
    if isinstance(value, str):
        return f"the string '{escaped(value, 24)}'"
    return {bool: "a boolean", dict: "an object", list: "a list", type(None): "null"}.get(type(value),
                                                                                          type(value).__name__)


def _names(value: object, key: str) -> list[str]:
    if not isinstance(value, list):
        raise ParameterError(f"{key}: must be a list of names, got {_kind(value)}")
    try:  # by the rule for names; a bad controller is a bad argument (ParameterError), not a bad scenario
        return [check_name(name, f"{key}[{i}]") if isinstance(name, str) else _not_a_name(name, f"{key}[{i}]")
                for i, name in enumerate(value)]
    except ScenarioError as error:
        raise ParameterError(str(error)) from None


def _not_a_name(value: object, key: str) -> str:
    raise ParameterError(f"{key}: must be a name (a string), got {_kind(value)}")


def check_states(n: int, key: str) -> None:
    """Refuse a controller of more than :data:`MAX_STATES` states (one :class:`ParameterError` naming ``key``,
    the count and the limit), before any work on its matrices."""
    if n > MAX_STATES:
        raise ParameterError(f"{key}: {n} states, more than the {MAX_STATES} a controller may have (each sample "
                             f"costs states^2 operations; reduce the design, e.g. by balanced truncation)")


def check_controller_data(data: object) -> dict[str, Any]:
    """The keyword arguments of :class:`DiscreteController` from ``controller.json``'s data, checked by the
    schema (see the module's description).

    Raises
    ------
    ParameterError
        Naming ``controller.<key>``: not an object, a missing key, a value of the wrong type.
    """
    if not isinstance(data, Mapping):
        raise ParameterError(f"controller: must be a JSON object, got {_kind(data)}")
    for key in data:  # warned about, not refused: a newer writer may record more (the contract says "at least")
        if key not in CONTROLLER_KEYS:
            warnings.warn(f"controller.{escaped(key, 40)}: unknown key, ignored (known: {', '.join(CONTROLLER_KEYS)})",
                          RuntimeWarning, stacklevel=3)
    if missing := [key for key in ("sample_rate", "sensors", "actuators") if key not in data]:
        raise ParameterError(f"controller.{missing[0]}: missing from the controller's JSON")
    rate = data["sample_rate"]
    if not _is_number(rate):
        raise ParameterError(f"controller.sample_rate: must be a number [Hz], got {_kind(rate)}")
    out: dict[str, Any] = {"sample_rate": float(rate)}
    for key in ("sensors", "actuators", "carriages"):
        out[key] = _names(data.get(key, []), f"controller.{key}")
    for key, kind, default in (("method", str, "custom"), ("delay", bool, False), ("settings", dict, {}),
                               ("robustness", dict, {})):
        value = data.get(key, default)
        if not isinstance(value, kind):
            what = {str: "a string", bool: "true or false", dict: "an object"}[kind]
            raise ParameterError(f"controller.{key}: must be {what}, got {_kind(value)}")
        out[key] = value
    del out["robustness"]
    schedule = data.get("schedule")
    if schedule:
        if not isinstance(schedule, list):
            raise ParameterError(f"controller.schedule: must be a list of design points, got {_kind(schedule)}")
        for i, e in enumerate(schedule):  # the state count first: no work on a matrix too large to run
            if isinstance(e, Mapping) and isinstance(e.get("A"), list):
                check_states(len(e["A"]), f"controller.schedule[{i}].A")
        out["schedule"] = [_entry(e, f"controller.schedule[{i}]") for i, e in enumerate(schedule)]
        carriage = data.get("schedule_carriage", 0)
        if isinstance(carriage, bool) or not isinstance(carriage, int):
            raise ParameterError(f"controller.schedule_carriage: must be a whole number, got {_kind(carriage)}")
        out["schedule_carriage"] = carriage
        return out
    if isinstance(data.get("A"), list):  # the state count first: no work on a matrix too large to run
        check_states(len(data["A"]), "controller.A")
    for key in _MATRICES:
        if key not in data:
            raise ParameterError(f"controller.{key}: missing (the matrices A, B, C, D, or a schedule)")
        out[key] = _matrix(data[key], f"controller.{key}")
    return out


def _entry(entry: object, key: str) -> dict[str, Any]:
    """One ``schedule`` entry: ``q`` and the four matrices."""
    if not isinstance(entry, Mapping):
        raise ParameterError(f"{key}: must be an object with q, A, B, C, D, got {_kind(entry)}")
    for name in entry:
        if name not in _ENTRY_KEYS:
            raise ParameterError(f"{key}.{escaped(name, 40)}: unknown key (known: {', '.join(_ENTRY_KEYS)})")
    if missing := [name for name in _ENTRY_KEYS if name not in entry]:
        raise ParameterError(f"{key}.{missing[0]}: missing (each design point has q, A, B, C, D)")
    return {"q": _numbers(entry["q"], f"{key}.q"), **{k: _matrix(entry[k], f"{key}.{k}") for k in _MATRICES}}


def spectral_radius(matrices: Sequence[np.ndarray]) -> float:
    """The largest spectral radius of the ``A`` matrices given (0 for a static gain)."""
    return max((float(np.max(np.abs(np.linalg.eigvals(a)), initial=0.0)) for a in matrices if a.size), default=0.0)


def warn_if_unstable(matrices: Sequence[np.ndarray], source: str) -> None:
    """One warning when a controller's ``A`` (any design point's) has an eigenvalue outside the unit circle."""
    radius = spectral_radius(matrices)
    if radius > 1.0 + 1e-9 and math.isfinite(radius):
        warnings.warn(f"{source}: the controller is unstable on its own (the spectral radius of A is {radius:.6g} "
                      "> 1): it diverges unless the loop it closes stabilises it", RuntimeWarning, stacklevel=3)
