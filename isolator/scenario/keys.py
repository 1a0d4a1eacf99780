"""Reading a TOML table key by key, every problem one :class:`ScenarioError` naming the key path."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from isolator.errors import ScenarioError

__all__ = ["KeyReader", "number", "number_list", "table_of_tables"]


_UNIT_TOL = 1e-6


class KeyReader:
    """Reads one TOML table, checking keys and values, naming paths in errors."""

    def __init__(self, data: Any, path: str) -> None:
        if not isinstance(data, Mapping):
            raise ScenarioError(f"{path or 'scenario'}: must be a table of keys")
        self.data = data
        self.path = path
        self.used: set[str] = set()

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def has(self, name: str) -> bool:
        return name in self.data

    def raw(self, name: str, default: Any = ..., required: bool = True) -> Any:
        self.used.add(name)
        if name in self.data:
            return self.data[name]
        if default is not ... or not required:
            return None if default is ... else default
        raise ScenarioError(f"{self.key(name)}: missing")

    def number(
        self,
        name: str,
        default: Any = ...,
        *,
        positive: bool = False,
        nonnegative: bool = False,
        below: float | None = None,
    ) -> float:
        value = self.raw(name, default)
        return number(value, self.key(name), positive=positive, nonnegative=nonnegative, below=below)

    def vector(
        self, name: str, default: Any = ..., *, positive: bool = False, nonnegative: bool = False
    ) -> tuple[float, float, float]:
        value = self.raw(name, default)
        key = self.key(name)
        if not isinstance(value, list | tuple) or len(value) != 3:
            raise ScenarioError(f"{key}: must be a list of three numbers")
        a, b, c = (number(v, f"{key}[{i}]", positive=positive, nonnegative=nonnegative) for i, v in enumerate(value))
        return a, b, c

    def unit_vector(self, name: str) -> tuple[float, float, float]:
        vec = self.vector(name)
        norm = math.sqrt(sum(v * v for v in vec))
        if norm == 0.0:
            raise ScenarioError(f"{self.key(name)}: must be a unit vector, got zero length")
        if abs(norm - 1.0) > _UNIT_TOL:
            raise ScenarioError(f"{self.key(name)}: must be a unit vector, got length {norm:.6g}")
        return vec[0] / norm, vec[1] / norm, vec[2] / norm

    def string(self, name: str, default: Any = ...) -> str:
        value = self.raw(name, default)
        if not isinstance(value, str):
            raise ScenarioError(f"{self.key(name)}: must be a string")
        return value

    def finish(self) -> None:
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            allowed = ", ".join(sorted(self.used))
            raise ScenarioError(f"{self.key(unknown[0])}: unknown key (allowed here: {allowed})")


def number(
    value: Any,
    key: str,
    *,
    positive: bool = False,
    nonnegative: bool = False,
    below: float | None = None,
) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ScenarioError(f"{key}: must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ScenarioError(f"{key}: must be finite, got {value}")
    if positive and value <= 0:
        raise ScenarioError(f"{key}: must be > 0, got {value:g}")
    if nonnegative and value < 0:
        raise ScenarioError(f"{key}: must be >= 0, got {value:g}")
    if below is not None and value >= below:
        raise ScenarioError(f"{key}: must be < {below:g}, got {value:g}")
    return value


def table_of_tables(data: Mapping, name: str) -> list:
    value = data.get(name, [])
    if not isinstance(value, list):
        raise ScenarioError(f"{name}: must be an array of tables ([[{name}]])")
    return value


def number_list(r: KeyReader, name: str) -> list[float]:
    value = r.raw(name)
    if not isinstance(value, list) or not value:
        raise ScenarioError(f"{r.key(name)}: must be a non-empty list of numbers")
    return [number(v, f"{r.key(name)}[{i}]") for i, v in enumerate(value)]
