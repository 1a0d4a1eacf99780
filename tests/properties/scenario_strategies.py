"""Hypothesis strategies for the property tests: valid scenarios as dictionaries, and one field broken.

Imported as a plain module from the tests of this folder (``from scenario_strategies import ...``),
like ``conftest``. The scenarios are valid by construction (at least three isolators spread round the
table, carriage chains that stay above the footprint); the tests ``assume`` away the few that the
reader still refuses or that would tip.
"""

from __future__ import annotations

import copy
import math
from typing import Any

from hypothesis import strategies as st

#: the structures drawn stay few, so that each compiled model is reused across examples
MAX_CARRIAGES = 2


def _floats(lo: float, hi: float) -> st.SearchStrategy[float]:
    # allow_subnormal=False: a compiled model (-ffast-math) sets flush-to-zero for the whole process
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False, allow_subnormal=False)


@st.composite
def isolator_layouts(draw: st.DrawFn, length: float, width: float) -> list[dict[str, Any]]:
    """Three to five spring-dampers spread round the table (never on one line)."""
    n = draw(st.integers(3, 5))
    isolators = []
    for k in range(n):
        angle = 2 * math.pi * k / n + draw(_floats(-0.4, 0.4))
        radius = draw(_floats(0.6, 0.95))
        position = [radius * length / 2 * math.cos(angle), radius * width / 2 * math.sin(angle),
                    -draw(_floats(0.05, 0.3))]
        isolators.append({
            "position": position,
            "stiffness": [draw(_floats(1e5, 1e6)) for _ in range(3)],
            "damping": [draw(_floats(1e3, 2e4)) for _ in range(3)],
        })
    return isolators


@st.composite
def profiles(draw: st.DrawFn, moving: bool = True) -> dict[str, Any]:
    """A trapezoid or an S-curve (``moving=False``: of zero stroke, the carriage stays put)."""
    kind = draw(st.sampled_from(["trapezoid", "scurve"]))
    stroke = draw(_floats(0.02, 0.15)) * draw(st.sampled_from([-1.0, 1.0])) if moving else 0.0
    profile: dict[str, Any] = {
        "type": kind,
        "start": draw(_floats(-0.05, 0.05)),
        "stroke": stroke,
        "velocity": draw(_floats(0.1, 0.5)),
        "acceleration": draw(_floats(0.5, 3.0)),
        "t0": draw(_floats(0.0, 0.3)),
    }
    if draw(st.booleans()):
        profile["deceleration"] = draw(_floats(0.5, 3.0))
    if kind == "scurve":
        profile["jerk"] = draw(_floats(10.0, 50.0))
    return profile


@st.composite
def unit_axes(draw: st.DrawFn) -> list[float]:
    """A direction mostly in the table's plane."""
    heading = draw(_floats(-math.pi, math.pi))
    tilt = draw(_floats(-0.3, 0.3))
    return [math.cos(heading) * math.cos(tilt), math.sin(heading) * math.cos(tilt), math.sin(tilt)]


@st.composite
def scenario_dicts(draw: st.DrawFn, moving: bool = True, min_carriages: int = 0,
                   duration: float = 5.0, sample_rate: float = 100.0) -> dict[str, Any]:
    """A valid spring-damper scenario: a box table, an isolator layout, a carriage chain, S-curves and trapezoids."""
    length, width = draw(_floats(1.5, 3.0)), draw(_floats(1.2, 2.0))
    n = draw(st.integers(min_carriages, MAX_CARRIAGES))
    carriages = []
    for i in range(n):
        parent = "table" if i == 0 else draw(st.sampled_from(["table", *(c["name"] for c in carriages)]))
        carriages.append({
            "name": f"c{i}",
            "mass": draw(_floats(20.0, 500.0)),
            "parent": parent,
            "axis": draw(unit_axes()),
            "origin": [draw(_floats(-0.05, 0.05)), draw(_floats(-0.05, 0.05)),
                       draw(_floats(0.05, 0.3)) if parent == "table" else draw(_floats(0.0, 0.1))],
            "profile": draw(profiles(moving)),
        })
    return {
        "name": "generated",
        "table": {"mass": draw(_floats(500.0, 5000.0)), "size": [length, width, draw(_floats(0.1, 0.4))]},
        "isolators": draw(isolator_layouts(length, width)),
        "carriages": carriages,
        "simulation": {"duration": duration, "sample_rate": sample_rate},
    }


def mirrored(data: dict[str, Any]) -> dict[str, Any]:
    """The scenario's mirror image in the x-z plane (y -> -y)."""
    out = copy.deepcopy(data)
    for iso in out["isolators"]:
        iso["position"][1] = -iso["position"][1]
    for c in out["carriages"]:
        c["axis"][1] = -c["axis"][1]
        c["origin"][1] = -c["origin"][1]
    return out


def scaled(data: dict[str, Any], factor: float) -> dict[str, Any]:
    """Every mass, stiffness and damping (and so the box inertia) times ``factor``."""
    out = copy.deepcopy(data)
    out["table"]["mass"] *= factor
    for iso in out["isolators"]:
        iso["stiffness"] = [factor * k for k in iso["stiffness"]]
        iso["damping"] = [factor * c for c in iso["damping"]]
    for c in out["carriages"]:
        c["mass"] *= factor
    return out


# -- one field broken --------------------------------------------------------------------------------
NAN = float("nan")

#: (how to find the field, bad values) for the numbers of a scenario dictionary; the path's ``{i}``
#: is an isolator or carriage index, ``{j}`` a vector component
NUMBER_BREAKS: list[tuple[str, list[Any]]] = [
    ("table.mass", [0.0, -1.0, NAN, math.inf, "heavy"]),
    ("table.size[{j}]", [0.0, -2.0, NAN]),
    ("gravity", [-9.81, NAN]),
    ("isolators[{i}].stiffness[{j}]", [-1.0, -5e5, NAN]),
    ("isolators[{i}].damping[{j}]", [-5.0, NAN, -math.inf]),
    ("isolators[{i}].position[{j}]", [NAN, math.inf]),
    ("carriages[{i}].mass", [0.0, -10.0, NAN]),
    ("carriages[{i}].origin[{j}]", [NAN]),
    ("carriages[{i}].profile.velocity", [0.0, -0.2, NAN]),
    ("carriages[{i}].profile.acceleration", [0.0, -1.0, NAN]),
    ("carriages[{i}].profile.t0", [-0.5, NAN]),
    ("carriages[{i}].profile.stroke", [NAN]),
    ("simulation.sample_rate", [0.0, -100.0, NAN]),
]

#: whole-value breaks: (path, bad value, the message's key when it is not the path)
VALUE_BREAKS: list[tuple[str, Any]] = [
    ("carriages[{i}].axis", [0.0, 0.0, 0.0]),
    ("carriages[{i}].axis", [1.0, 1.0, 0.0]),
    ("carriages[{i}].axis", [NAN, 0.0, 1.0]),
    ("carriages[{i}].parent", "nowhere"),
    ("carriages[{i}].mass", True),
]


def _split(path: str) -> list[str | int]:
    parts: list[str | int] = []
    for piece in path.split("."):
        name, *indices = piece.replace("]", "").split("[")
        parts.append(name)
        parts += [int(k) for k in indices]
    return parts


def set_path(data: dict[str, Any], path: str, value: Any) -> dict[str, Any]:
    """A copy of ``data`` with the value at a key path (``isolators[1].damping[2]``) replaced."""
    out = copy.deepcopy(data)
    parts = _split(path)
    node: Any = out
    for part in parts[:-1]:
        node = node[part]
    node[parts[-1]] = value
    return out


@st.composite
def broken_scenarios(draw: st.DrawFn) -> tuple[dict[str, Any], str, Any, dict[str, Any]]:
    """A valid scenario with one field broken: (the dictionary, the broken key path, the bad value, the valid one)."""
    data = draw(scenario_dicts(min_carriages=1))
    if draw(st.booleans()):
        template, values = draw(st.sampled_from(NUMBER_BREAKS))
        value = draw(st.sampled_from(values))
    else:
        template, value = draw(st.sampled_from(VALUE_BREAKS))
    path = template.format(i=draw(st.integers(0, 2)) if "isolators" in template else
                           draw(st.integers(0, len(data["carriages"]) - 1)), j=draw(st.integers(0, 2)))
    if path == "gravity":
        data["gravity"] = 9.81
    return set_path(data, path, value), path, value, data
