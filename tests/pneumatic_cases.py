"""Pneumatic scenarios for the tests, as dictionaries (``scenario_from_dict`` builds them)."""

from __future__ import annotations

import copy
from typing import Any

CORNERS = ((1.0, 0.5), (-1.0, 0.5), (-1.0, -0.5), (1.0, -0.5))
NAMES = ("front-left", "rear-left", "rear-right", "front-right")


def air_spring(name: str, x: float, y: float, *, area: float = 0.03, volume: float = 6.4e-4,
               damping_volume: float = 1.28e-3, diameter: float = 5.4e-4, hs: float = 0.15) -> dict[str, Any]:
    """One pneumatic isolator at (x, y, -hs)."""
    out: dict[str, Any] = {
        "name": name, "model": "pneumatic", "position": [x, y, -hs], "area": area, "volume": volume,
        "damping_volume": damping_volume, "horizontal_stiffness": [5.7e5, 5.7e5],
        "horizontal_damping": [5.7e3, 5.7e3],
    }
    if damping_volume > 0:
        out["orifice"] = {"diameter": diameter, "length": 5.0e-3}
    return out


def valve(gain: float = 0.2, deadband: float = 2.0e-5, max_flow: float = 1.0e-3) -> dict[str, float]:
    return {"gain": gain, "deadband": deadband, "max_flow": max_flow}


def pneumatic_dict(*, valves: bool = True, polytropic: float = 1.4, carriage: bool = True,
                   stroke: float = 0.8, duration: float = 4.0, **iso: Any) -> dict[str, Any]:
    """The paper's table on four air springs in three groups (front pair on one valve), one x carriage."""
    groups: list[dict[str, Any]] = [
        {"name": "front", "isolators": ["front-left", "front-right"], "line": {"diameter": 2.5e-3, "length": 2.0}},
        {"name": "rear-left", "isolators": ["rear-left"]},
        {"name": "rear-right", "isolators": ["rear-right"]},
    ]
    if valves:
        for g in groups:
            g["valve"] = valve()
    data: dict[str, Any] = {
        "name": "pneumatic-test",
        "table": {"mass": 4400.0, "size": [2.0, 1.0, 0.3]},
        "air": {"polytropic": polytropic},
        "isolators": [air_spring(n, x, y, **iso) for n, (x, y) in zip(NAMES, CORNERS, strict=True)],
        "leveling": groups,
        "simulation": {"duration": duration, "sample_rate": 1000.0},
    }
    if carriage:
        data["carriages"] = [{
            "name": "x-stage", "mass": 400.0, "parent": "table", "axis": [1.0, 0.0, 0.0],
            "origin": [0.0, 0.0, 0.35],
            "profile": {"type": "scurve", "start": 0.0, "stroke": stroke, "velocity": 0.4,
                        "acceleration": 1.0, "jerk": 20.0, "t0": 0.2},
        }]
    return data


def three_springs_dict(**iso: Any) -> dict[str, Any]:
    """Three air springs, each its own group (no ``[[leveling]]``), symmetric about the x axis, no carriage.

    The front one at (1, 0) carries half the weight with twice the area, so all three sit at one pressure.
    """
    data = pneumatic_dict(carriage=False)
    front = air_spring("front", 1.0, 0.0, **{**iso, "area": 2 * iso.get("area", 0.03),
                                              "volume": 2 * iso.get("volume", 6.4e-4),
                                              "damping_volume": 2 * iso.get("damping_volume", 1.28e-3)})
    data["isolators"] = [front, air_spring("rear-left", -1.0, 0.5, **iso), air_spring("rear-right", -1.0, -0.5, **iso)]
    del data["leveling"]
    return copy.deepcopy(data)
