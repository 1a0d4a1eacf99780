"""Scenario files written back: a source file's keys with some values replaced (optimised profiles, fitted
parameters), relative ``file`` keys (and ``table.flexible.modes``) made absolute so that the written file loads
from anywhere."""

from __future__ import annotations

import re
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from isolator.scenario.output_files import atomic_output
from isolator.scenario.reader import resolve_scenario_path

__all__ = ["absolute_files", "scenario_data", "set_parameter", "write_toml"]

_COMPONENTS = {"x": 0, "y": 1, "z": 2}
_TOKEN = re.compile(r"([^.\[\]]+)|\[(\d+)\]")


def absolute_files(data: Any, base: Path, parent: str = "") -> None:
    """Make every relative file name under ``data`` absolute (relative to ``base``): each ``file`` key, and the
    ``modes`` of a ``flexible`` table (``parent``: the key ``data`` is under)."""
    if isinstance(data, dict):
        for key, value in data.items():
            named = key == "file" or (key == "modes" and parent == "flexible")
            if named and isinstance(value, str) and not Path(value).is_absolute():
                data[key] = str((base / value).resolve())
            else:
                absolute_files(value, base, key)
    elif isinstance(data, list):
        for item in data:
            absolute_files(item, base)


def scenario_data(source: str | Path | None) -> tuple[Path, dict[str, Any]]:
    """A scenario file (or bundled name) and its keys, relative ``file`` keys made absolute."""
    origin = resolve_scenario_path(source)
    with open(origin, "rb") as handle:
        data = tomllib.load(handle)
    absolute_files(data, origin.parent)
    return origin, data


def write_toml(data: Mapping[str, Any], path: str | Path) -> Path:
    """Write ``data`` as TOML to ``path`` (its folder made); returns the path."""
    import tomli_w

    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(target, "wb") as handle:
        tomli_w.dump(data, handle)
    return target


def set_parameter(data: dict[str, Any], name: str, value: float, values: Mapping[str, float]) -> None:
    """Set the parameter ``name`` (a ``ParameterLayout`` name, ``isolators[0].stiffness.z``) to ``value`` in a
    scenario's keys; a vector the file leaves out (a table's box inertia) is written whole from ``values``
    (every parameter's current value by name)."""
    tokens = [(m.group(1), m.group(2)) for m in _TOKEN.finditer(name)]
    node: Any = data
    path = ""
    for k, (key, index) in enumerate(tokens):
        last = k == len(tokens) - 1
        if index is not None:
            node = node[int(index)]
            path += f"[{index}]"
            continue
        if isinstance(node, list) and key in _COMPONENTS:
            node[_COMPONENTS[key]] = value
            return
        if last:
            node[key] = value
            return
        nxt_key = tokens[k + 1][0]
        if key not in node:
            prefix = f"{path}.{key}" if path else key
            if nxt_key in _COMPONENTS:
                node[key] = [values[f"{prefix}.{a}"] for a in "xyz" if f"{prefix}.{a}" in values]
            else:
                node[key] = {}
        node = node[key]
        path = f"{path}.{key}" if path else key
