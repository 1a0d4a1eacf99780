"""Pneumatic keys: the bundled scenarios read, and every bad value is one error naming its key."""

from __future__ import annotations

import copy
import re
from typing import Any

import numpy as np
import pytest
from pneumatic_cases import pneumatic_dict, three_springs_dict

from isolator import load_scenario, scenario_from_dict
from isolator.errors import ScenarioError
from isolator.scenario.pneumatic import PneumaticIsolator
from isolator.scenario.validation import rest_gauge_pressures


def _error(data: dict[str, Any]) -> str:
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(copy.deepcopy(data))
    return str(info.value)


def test_bundled_pneumatic_scenarios_read():
    for name in ("paper-table-3-2-pneumatic", "paper-table-3-2-pneumatic-3", "paper-table-3-2-pneumatic-active"):
        s = load_scenario(name)
        assert s.is_pneumatic
        assert len(s.leveling) == 3
        assert all(isinstance(iso, PneumaticIsolator) for iso in s.isolators)
        assert all(g.valve is not None for g in s.leveling)


def test_defaults_and_groups():
    s = scenario_from_dict(three_springs_dict())
    assert s.air is not None
    assert s.air.atmosphere == 101325.0
    assert s.air.polytropic == 1.4
    # three isolators without [[leveling]]: each its own group, sensor at the isolator, no valve
    assert [g.isolators for g in s.leveling] == [(0,), (1,), (2,)]
    assert [g.sensor for g in s.leveling] == [(1.0, 0.0), (-1.0, 0.5), (-1.0, -0.5)]
    assert all(g.valve is None and g.supply == 6.0e5 for g in s.leveling)
    # the sensor defaults to the centroid of the group's isolators
    s4 = scenario_from_dict(pneumatic_dict())
    assert s4.leveling[0].sensor == (1.0, 0.0)


def test_rest_pressures_hold_the_table_level():
    """Hand statics: the groups' forces balance the weight and its moments."""
    s = scenario_from_dict(pneumatic_dict(stroke=0.8))
    for q in (s.initial_positions(), s.final_positions()):
        p = rest_gauge_pressures(s, q)
        force = np.zeros(3)  # Fz, Mx, My about the table's mass centre
        for g, pg in zip(s.leveling, p, strict=True):
            for k in g.isolators:
                x, y, _ = s.isolators[k].position
                f = pg * s.isolators[k].area
                force += [f, y * f, -x * f]
        xc = s.carriage_positions(q)[0]
        weight = s.gravity * np.array([s.total_mass, 0.0, 0.0])
        moment = -s.gravity * s.carriages[0].mass * np.array([0.0, xc[1], -xc[0]])
        np.testing.assert_allclose(force - weight + np.array([0.0, *moment[1:]]), 0.0, atol=1e-6)


def _set(data: dict[str, Any], path: str, value: Any) -> dict[str, Any]:
    out = copy.deepcopy(data)
    node: Any = out
    parts = re.findall(r"[^.\[\]]+", path)
    for part in parts[:-1]:
        node = node[int(part)] if part.isdigit() else node[part]
    last = parts[-1]
    if value is ...:
        del node[int(last) if last.isdigit() else last]
    elif last.isdigit():
        node[int(last)] = value
    else:
        node[last] = value
    return out


BAD = [
    ("isolators.0.area", 0.0, r"^isolators\[0\]\.area: must be > 0"),
    ("isolators.1.volume", -1e-3, r"^isolators\[1\]\.volume: must be > 0"),
    ("isolators.2.damping_volume", -1e-3, r"^isolators\[2\]\.damping_volume: must be >= 0"),
    ("isolators.0.orifice.diameter", 0.0, r"^isolators\[0\]\.orifice\.diameter: must be > 0"),
    ("isolators.0.orifice.length", 0.0, r"^isolators\[0\]\.orifice\.length: must be > 0"),
    ("isolators.0.orifice", ..., r"^isolators\[0\]\.orifice: missing \(required when damping_volume > 0\)"),
    ("isolators.0.name", ..., r"^isolators\[0\]\.name: required for a pneumatic isolator"),
    ("isolators.0.horizontal_stiffness", ..., r"^isolators\[0\]\.horizontal_stiffness: missing"),
    ("isolators.0.model", "air", r"^isolators\[0\]\.model: must be 'spring-damper' or 'pneumatic'"),
    ("leveling.0.isolators", ["front-left"], r"^isolators\[3\]: pneumatic isolator 'front-right' is in no"),
    ("leveling.1.isolators", ["front-left"],
     r"^leveling\[1\]\.isolators: 'front-left' is already in group 'front'"),
    ("leveling.1.isolators", ["nowhere"], r"^leveling\[1\]\.isolators: unknown isolator 'nowhere'"),
    ("leveling.0.line", ..., r"^leveling\[0\]\.line: missing \(required for a group of two or more"),
    ("leveling.2", ..., r"^leveling: exactly three groups are required, got 2"),
    ("leveling", ..., r"^leveling: missing; 4 pneumatic isolators need exactly three"),
    ("leveling.0.valve.deadband", -1.0, r"^leveling\[0\]\.valve\.deadband: must be >= 0"),
    ("leveling.0.valve.max_flow", 0.0, r"^leveling\[0\]\.valve\.max_flow: must be > 0"),
    ("leveling.0.line.length", 0.0, r"^leveling\[0\]\.line\.length: must be > 0"),
    ("leveling.0.supply", 1.0e5,
     r"^leveling\[0\]\.supply: group 'front' needs a rest gauge pressure of 3\.\d+e\+05 Pa"),
    ("air.polytropic", 0.9, r"^air\.polytropic: must be in \[1, 1\.67\], got 0\.9"),
    ("air.polytropic", 1.8, r"^air\.polytropic: must be in \[1, 1\.67\], got 1\.8"),
    ("air.viscosity", 0.0, r"^air\.viscosity: must be > 0"),
    ("air.unknown", 1.0, r"^air\.unknown: unknown key"),
]


@pytest.mark.parametrize(("path", "value", "message"), BAD, ids=[f"{p}={v}" for p, v, _ in BAD])
def test_bad_pneumatic_input_is_named(path: str, value: Any, message: str):
    assert re.search(message, _error(_set(pneumatic_dict(), path, value)))


def test_mixed_isolators_are_refused():
    data = pneumatic_dict()
    data["isolators"][2] = {"position": [-1.0, -0.5, -0.15], "stiffness": [1e5] * 3, "damping": [1e3] * 3}
    assert re.search(r"^isolators\[2\]\.model: a scenario's isolators are all pneumatic or all spring-damper",
                     _error(data))


def test_pneumatic_keys_in_a_spring_damper_scenario_are_refused():
    from conftest import base_dict

    assert _error({**base_dict(), "air": {}}).startswith("air: only for pneumatic isolators")
    assert _error({**base_dict(), "leveling": []}).startswith("leveling: only for pneumatic isolators")


def test_a_group_that_would_pull_the_table_down_is_named():
    """The front pair acts at (1, 0): a heavy load forward and to the left lifts the rear-right group."""
    data = pneumatic_dict()
    data["carriages"][0]["mass"] = 20000.0
    data["carriages"][0]["origin"] = [0.0, 0.45, 0.35]
    data["carriages"][0]["profile"]["start"] = 0.9
    data["carriages"][0]["profile"]["stroke"] = 0.05
    for group in data["leveling"]:
        group["supply"] = 1e8
    msg = _error(data)
    assert re.search(r"^leveling\[2\]: group 'rear-right' would need a gauge pressure of -[\d.e+]+ Pa at rest", msg)


def test_groups_whose_statics_are_singular_are_named():
    """A diagonal pair in one group carries no moment of its own: the three pressures are not unique."""
    data = pneumatic_dict()
    data["leveling"][0]["isolators"] = ["front-left", "rear-right"]
    data["leveling"][1]["isolators"] = ["rear-left"]
    data["leveling"][2]["isolators"] = ["front-right"]
    assert _error(data).startswith("leveling: the groups' isolators make the statics singular")
