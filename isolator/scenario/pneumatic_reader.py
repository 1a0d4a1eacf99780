"""Reading ``[air]``, pneumatic ``[[isolators]]`` and ``[[leveling]]`` (``docs/scenario-format.md``).

Every problem is one :class:`ScenarioError` naming the key.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from isolator.errors import ScenarioError
from isolator.scenario.definitions import Isolator
from isolator.scenario.keys import KeyReader, number, table_of_tables
from isolator.scenario.pneumatic import Air, Capillary, LevelingGroup, PneumaticIsolator, Valve

__all__ = ["read_air", "read_leveling", "read_pneumatic_isolator", "read_pneumatics"]

#: the polytropic exponent's allowed range (isothermal .. a little above diatomic adiabatic)
POLYTROPIC_RANGE = (1.0, 1.67)


def read_air(r: KeyReader) -> Air:
    """The ``[air]`` table (every key optional)."""
    default = Air()
    air = Air(
        atmosphere=r.number("atmosphere", default.atmosphere, positive=True),
        temperature=r.number("temperature", default.temperature, positive=True),
        gas_constant=r.number("gas_constant", default.gas_constant, positive=True),
        viscosity=r.number("viscosity", default.viscosity, positive=True),
        polytropic=r.number("polytropic", default.polytropic, positive=True),
    )
    low, high = POLYTROPIC_RANGE
    if not low <= air.polytropic <= high:
        raise ScenarioError(f"{r.key('polytropic')}: must be in [{low:g}, {high:g}], got {air.polytropic:g}")
    r.finish()
    return air


def _capillary(r: KeyReader, name: str) -> Capillary:
    cap = KeyReader(r.raw(name), r.key(name))
    out = Capillary(diameter=cap.number("diameter", positive=True), length=cap.number("length", positive=True))
    cap.finish()
    return out


def _pair(r: KeyReader, name: str, *, nonnegative: bool = False) -> tuple[float, float]:
    value = r.raw(name)
    key = r.key(name)
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise ScenarioError(f"{key}: must be a list of two numbers")
    a, b = (number(v, f"{key}[{i}]", nonnegative=nonnegative) for i, v in enumerate(value))
    return a, b


def read_pneumatic_isolator(r: KeyReader) -> PneumaticIsolator:
    """One ``[[isolators]]`` block with ``model = "pneumatic"`` (``model`` already read)."""
    name = r.string("name") if r.has("name") else ""
    if not name:
        raise ScenarioError(f"{r.key('name')}: required for a pneumatic isolator (groups name it)")
    damping_volume = r.number("damping_volume", nonnegative=True)
    if damping_volume > 0 and not r.has("orifice"):
        raise ScenarioError(f"{r.key('orifice')}: missing (required when damping_volume > 0)")
    orifice = _capillary(r, "orifice") if r.has("orifice") else None
    r.used.add("orifice")
    iso = PneumaticIsolator(
        name=name,
        position=r.vector("position"),
        area=r.number("area", positive=True),
        volume=r.number("volume", positive=True),
        damping_volume=damping_volume,
        orifice=orifice,
        horizontal_stiffness=_pair(r, "horizontal_stiffness", nonnegative=True),
        horizontal_damping=_pair(r, "horizontal_damping", nonnegative=True),
    )
    r.finish()
    return iso


def _group(r: KeyReader, names: Sequence[str], index: int) -> tuple[LevelingGroup, bool]:
    """One group, and whether its sensor was left to the default (the isolators' centroid)."""
    name = r.string("name") if r.has("name") else f"group-{index + 1}"
    if not name:
        raise ScenarioError(f"{r.key('name')}: must be a non-empty name")
    members_raw = r.raw("isolators")
    if not isinstance(members_raw, list) or not members_raw or not all(isinstance(m, str) for m in members_raw):
        raise ScenarioError(f"{r.key('isolators')}: must be a non-empty list of isolator names")
    members: list[int] = []
    names = list(names)
    for m in members_raw:
        if m not in names:
            raise ScenarioError(f"{r.key('isolators')}: unknown isolator '{m}' (isolators: {', '.join(names)})")
        if names.index(m) in members:
            raise ScenarioError(f"{r.key('isolators')}: '{m}' is listed twice")
        members.append(names.index(m))
    if len(members) >= 2 and not r.has("line"):
        raise ScenarioError(f"{r.key('line')}: missing (required for a group of two or more isolators)")
    line = _capillary(r, "line") if r.has("line") else None
    r.used.add("line")
    sensor = _pair(r, "sensor") if r.has("sensor") else None
    r.used.add("sensor")
    valve = None
    if r.has("valve"):
        v = KeyReader(r.raw("valve"), r.key("valve"))
        valve = Valve(gain=v.number("gain", positive=True), deadband=v.number("deadband", nonnegative=True),
                      max_flow=v.number("max_flow", positive=True))
        v.finish()
    r.used.add("valve")
    supply = r.number("supply", 6.0e5, positive=True)
    r.finish()
    return LevelingGroup(name, tuple(members), line, sensor or (0.0, 0.0), valve, supply), sensor is None


def read_leveling(
    data: Mapping[str, Any], isolators: tuple[PneumaticIsolator, ...]
) -> tuple[LevelingGroup, ...]:
    """The ``[[leveling]]`` groups; three pneumatic isolators without any are three groups of one."""
    names = [iso.name for iso in isolators]
    for i, n in enumerate(names):
        if n in names[:i]:
            raise ScenarioError(f"isolators[{i}].name: '{n}' is used twice")
    blocks = table_of_tables(data, "leveling")
    if not blocks:
        if len(isolators) == 3:
            return tuple(LevelingGroup(iso.name, (k,), None, (iso.position[0], iso.position[1]))
                         for k, iso in enumerate(isolators))
        raise ScenarioError(
            f"leveling: missing; {len(isolators)} pneumatic isolators need exactly three [[leveling]] groups"
        )
    if len(blocks) != 3:
        raise ScenarioError(f"leveling: exactly three groups are required, got {len(blocks)}")
    groups = []
    for j, block in enumerate(blocks):
        group, centroid = _group(KeyReader(block, f"leveling[{j}]"), names, j)
        if centroid:
            xs = [isolators[k].position[0] for k in group.isolators]
            ys = [isolators[k].position[1] for k in group.isolators]
            group = LevelingGroup(group.name, group.isolators, group.line, (sum(xs) / len(xs), sum(ys) / len(ys)),
                                  group.valve, group.supply)
        groups.append(group)
    for j, g in enumerate(groups):
        if g.name in [h.name for h in groups[:j]]:
            raise ScenarioError(f"leveling[{j}].name: '{g.name}' is used twice")
    owner: dict[int, int] = {}
    for j, g in enumerate(groups):
        for k in g.isolators:
            if k in owner:
                raise ScenarioError(
                    f"leveling[{j}].isolators: '{names[k]}' is already in group '{groups[owner[k]].name}' "
                    "(every pneumatic isolator in exactly one group)"
                )
            owner[k] = j
    for k, n in enumerate(names):
        if k not in owner:
            raise ScenarioError(f"isolators[{k}]: pneumatic isolator '{n}' is in no [[leveling]] group")
    return tuple(groups)


def read_pneumatics(
    top: KeyReader, data: Mapping[str, Any], isolators: Sequence[Isolator | PneumaticIsolator]
) -> tuple[Air | None, tuple[LevelingGroup, ...]]:
    """``[air]`` and ``[[leveling]]`` of a pneumatic scenario; errors for them in a spring-damper one."""
    top.used.update(("air", "leveling"))
    pneumatic = [isinstance(iso, PneumaticIsolator) for iso in isolators]
    if not any(pneumatic):
        for key in ("air", "leveling"):
            if top.has(key):
                raise ScenarioError(f"{key}: only for pneumatic isolators (model = \"pneumatic\")")
        return None, ()
    if not all(pneumatic):
        i = pneumatic.index(False)
        raise ScenarioError(
            f"isolators[{i}].model: a scenario's isolators are all pneumatic or all spring-damper (mixed here)"
        )
    air = read_air(KeyReader(top.raw("air", {}), "air"))
    pneumatics = tuple(iso for iso in isolators if isinstance(iso, PneumaticIsolator))
    return air, read_leveling(data, pneumatics)
