"""Reading a TOML file, and a TOML table key by key: every problem one :class:`ScenarioError` naming the
file or the key path. A key missing where the table has a near spelling of it (``stifness``) is reported
as that unknown key with the suggestion, before any "missing" error.
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from collections.abc import Collection, Mapping
from functools import lru_cache
from pathlib import Path
from typing import Any

from isolator.errors import IsolatorError, ScenarioError
from isolator.scenario.files import long_integer, read_input
from isolator.scenario.names import escaped

__all__ = ["TOP_LEVEL_KEYS", "KeyReader", "check_placement", "load_toml", "number", "number_list", "table_of_tables"]


_UNIT_TOL = 1e-6

#: the keys of a scenario's top level
TOP_LEVEL_KEYS = ("name", "gravity", "table", "isolators", "air", "leveling", "simulation", "carriages",
                  "actuators", "settling", "ground", "points", "windows", "sequence",
                  "sensors", "disturbances")


def load_toml(path: Path, what: str = "scenario file") -> dict[str, Any]:
    """A TOML file's keys; a file that is not a regular one (:func:`~isolator.scenario.files.read_input`, named
    as ``what``), is not UTF-8, has a byte-order mark, is empty, is not valid TOML or nests too deeply is a
    :class:`ScenarioError` naming the file (and the line)."""
    shown = escaped(path, 120)
    if path.is_dir():
        raise ScenarioError(f"{shown}: is a folder, not a {what}")
    raw = read_input(path, what)
    if raw.startswith(b"\xef\xbb\xbf"):
        raise ScenarioError(f"{shown}: starts with a byte-order mark (BOM), which TOML does not allow; "
                            "save it as UTF-8 without BOM")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise ScenarioError(f"{shown} line {line}: not UTF-8 text (byte 0x{raw[exc.start]:02x}); "
                            "save the file as UTF-8") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{shown}: not valid TOML ({exc})") from None
    except RecursionError:
        raise ScenarioError(f"{shown}: nested too deeply (arrays or tables inside each other hundreds of "
                            "levels deep)") from None
    except ValueError:  # a whole number past Python's digit limit (tomllib's own errors are TOMLDecodeError)
        raise ScenarioError(f"{shown} {long_integer(text)}") from None
    if not data:
        raise ScenarioError(f"{shown}: is empty (a scenario needs at least [table] and [[isolators]])")
    return data


@lru_cache(maxsize=1)
def _known_keys() -> frozenset[str]:
    """Every key name the scenario's readers know: a key in a file that is one of them is no typo."""
    folder = Path(__file__).parent
    text = "".join((folder / name).read_text() for name in ("reader.py", "pneumatic_reader.py", "windows_reader.py",
                                                                 "sequence.py", "tables.py", "sensors.py",
                                                                 "ground_reader.py", "random_sources.py",
                                                                 "flexible/reader.py"))
    return frozenset(re.findall(r'"([a-z][a-z0-9_]*)"', text))


def _misspelt(data: Mapping, name: str, path: str, known: Collection[str]) -> ScenarioError | None:
    """The error for a key of ``data`` that looks like a misspelling of the absent key ``name``, if any."""
    candidates = [k for k in data if isinstance(k, str) and k not in known]
    close = difflib.get_close_matches(name, candidates, n=1, cutoff=0.75)
    if not close:
        return None
    key = f"{path}.{close[0]}" if path else close[0]
    return ScenarioError(f"{key}: unknown key; did you mean '{name}'?")


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
        typo = _misspelt(self.data, name, self.path, TOP_LEVEL_KEYS if not self.path else _known_keys())
        if typo is not None:
            raise typo
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
        rule: Any = None,
    ) -> float:
        """The number at ``name``: finite, and as asked (``rule``: a :class:`~isolator.scenario.rules.Rule`)."""
        value = number(self.raw(name, default), self.key(name), positive=positive, nonnegative=nonnegative,
                       below=below)
        problem = None if rule is None else rule.problem(value)
        if problem is not None:
            raise ScenarioError(f"{self.key(name)}: {problem}")
        return value

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
            close = difflib.get_close_matches(unknown[0], sorted(self.used), n=1, cutoff=0.75)
            if close:
                raise ScenarioError(f"{self.key(unknown[0])}: unknown key; did you mean '{close[0]}'?")
            allowed = ", ".join(sorted(self.used))
            raise ScenarioError(f"{self.key(unknown[0])}: unknown key (allowed here: {allowed})")


def number(
    value: Any,
    key: str,
    *,
    positive: bool = False,
    nonnegative: bool = False,
    below: float | None = None,
    error: type[IsolatorError] = ScenarioError,
) -> float:
    """``value`` as a finite float, as asked; else ``error`` (default :class:`ScenarioError`) naming ``key``."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise error(f"{key}: must be a number, got {escaped(repr(value), 40)}")
    try:
        value = float(value)
    except OverflowError:  # a TOML integer beyond any float (10**400)
        raise error(f"{key}: must be finite, got an integer of {len(str(abs(value)))} digits") from None
    if not math.isfinite(value):
        raise error(f"{key}: must be finite, got {value}")
    if positive and value <= 0:
        raise error(f"{key}: must be > 0, got {value:g}")
    if nonnegative and value < 0:
        raise error(f"{key}: must be >= 0, got {value:g}")
    if below is not None and value >= below:
        raise error(f"{key}: must be < {below:g}, got {value:g}")
    return value


def table_of_tables(data: Mapping, name: str) -> list:
    if name not in data:
        typo = _misspelt(data, name, "", TOP_LEVEL_KEYS)
        if typo is not None:
            raise typo
    value = data.get(name, [])
    if not isinstance(value, list):
        raise ScenarioError(f"{name}: must be an array of tables ([[{name}]])")
    return value


def number_list(r: KeyReader, name: str) -> list[float]:
    value = r.raw(name)
    if not isinstance(value, list) or not value:
        raise ScenarioError(f"{r.key(name)}: must be a non-empty list of numbers")
    return [number(v, f"{r.key(name)}[{i}]") for i, v in enumerate(value)]


def check_placement(position: Any, direction: Any, key: str) -> None:
    """A built object's ``position`` and ``direction``: three finite numbers each, the direction a unit vector
    (to 1e-6); else one :class:`ScenarioError` naming ``key.position`` or ``key.direction``."""
    for field, vec in (("position", position), ("direction", direction)):
        if not isinstance(vec, tuple) or len(vec) != 3:
            raise ScenarioError(f"{key}.{field}: must be three numbers")
        for i, v in enumerate(vec):
            number(v, f"{key}.{field}[{i}]")
    norm = sum(v * v for v in direction) ** 0.5
    if abs(norm - 1.0) > _UNIT_TOL:
        raise ScenarioError(f"{key}.direction: must be a unit vector, got length {norm:.6g}")
