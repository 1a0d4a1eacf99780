"""Reading and validating scenario files (TOML) into :class:`Scenario` objects.

Every problem is reported as one :class:`ScenarioError` whose message starts
with the key path, for example ``carriages[1].profile.acceleration: must be > 0``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from isolator.errors import ScenarioError
from isolator.scenario.arguments import check_public, reading, register_conversion
from isolator.scenario.bundled import DEFAULT_SCENARIO as DEFAULT_SCENARIO
from isolator.scenario.bundled import bundled_scenarios, resolve_scenario_path
from isolator.scenario.definitions import (
    SIGNALS,
    Actuator,
    Carriage,
    Ground,
    Isolator,
    MotionLimits,
    Point,
    Scenario,
    Settling,
    SimulationSettings,
    Table,
)
from isolator.scenario.field_checks import register_field_checks
from isolator.scenario.flexible import read_feet, read_flexible
from isolator.scenario.flexible_checks import check_flexible
from isolator.scenario.ground_reader import read_spectrum
from isolator.scenario.keys import KeyReader, load_toml, number, table_of_tables
from isolator.scenario.names import FORMULA_STARTS, MAX_NAME, escaped
from isolator.scenario.pneumatic import PneumaticIsolator
from isolator.scenario.pneumatic_reader import read_pneumatic_isolator, read_pneumatics
from isolator.scenario.profile_shapes import samples, scurve, trapezoid
from isolator.scenario.profiles import Profile, SineProfile
from isolator.scenario.random_sources import read_density, read_disturbances
from isolator.scenario.rules import MOTION, check_scenario_values
from isolator.scenario.sensors import read_sensors
from isolator.scenario.sequence import StepSequence, held, read_sequence
from isolator.scenario.tables import load_spectrum, read_csv_columns, read_samples
from isolator.scenario.validation import (
    check_carriage_tree,
    check_extent,
    check_isolator_layout,
    check_pneumatics,
    check_sequence,
    check_unique_names,
)
from isolator.scenario.windows_reader import read_windows

__all__ = ["bundled_scenarios", "load_scenario", "load_spectrum", "read_csv_columns", "resolve_scenario_path",
           "scenario_from_dict"]

def load_scenario(spec: str | Path | None = None) -> Scenario:
    """Read and validate a scenario.

    Parameters
    ----------
    spec : str or Path or None
        A TOML file, or the name of a bundled scenario (:func:`bundled_scenarios`; ``isolator scenarios``
        lists them); None loads ``paper-table-3-2``. The bundled scenarios:

        - ``paper-table-3-1``: the paper's Table 3.1 case, one carriage in sinusoidal motion;
        - ``paper-table-3-2``: the paper's Table 3.2 case, an LCD-inspection XY stage on 4 isolators;
        - ``paper-table-3-2-active``: the same with three 500 N force actuators at each isolator;
        - ``paper-table-3-2-geophones``: the active table with a geophone at each actuator;
        - ``paper-table-3-2-budget``: the geophone table on a VC-D floor with random forces and noise (the
          error budget's example);
        - ``paper-table-3-2-flexible``: its granite top bending, with six elastic modes from
          ``paper-table-3-2-top-modes.csv`` (a tool on a bridge, a part, a VC-D floor);
        - ``paper-table-3-2-pneumatic``: on four air springs in three leveling groups;
        - ``paper-table-3-2-pneumatic-3``: on three air springs, one leveling valve each;
        - ``paper-table-3-2-pneumatic-active``: the pneumatic table with the active one's actuators;
        - ``paper-table-3-2-sequence``: the stage inspecting a 5 x 4 grid, step and settle.

    Returns
    -------
    Scenario
        The validated, frozen scenario.

    Raises
    ------
    ScenarioError
        With the offending key path and the reason.

    Examples
    --------
    >>> from isolator import load_scenario
    >>> round(load_scenario("paper-table-3-2").stop_time, 3)
    7.9
    >>> [carriage.name for carriage in load_scenario("paper-table-3-2").carriages]
    ['x-stage', 'y-stage']
    """
    path = resolve_scenario_path(spec)
    stem = escaped(path.stem)[:MAX_NAME].strip().lstrip(FORMULA_STARTS).strip()  # '-x.toml' is named 'x'
    return scenario_from_dict(load_toml(path), base_dir=path.parent, default_name=stem)


def scenario_from_dict(
    data: Mapping[str, Any], base_dir: Path | str = ".", default_name: str = "scenario"
) -> Scenario:
    """Validate a parsed scenario (the TOML's dictionary) into a :class:`Scenario`.

    Parameters
    ----------
    data : mapping
        The scenario's keys, as ``tomllib`` returns them.
    base_dir : path
        Folder that relative file names (sampled profiles) are read from.
    default_name : str
        Name used when the data has none.

    Returns
    -------
    Scenario
        The validated, frozen scenario.

    Raises
    ------
    ScenarioError
        A missing or bad key, named with its path and the reason.

    Examples
    --------
    >>> import tomllib
    >>> from isolator import bundled_scenarios, scenario_from_dict
    >>> data = tomllib.loads(bundled_scenarios()["paper-table-3-2"].read_text(encoding="utf-8"))
    >>> data["table"]["mass"] = 5000.0
    >>> scenario_from_dict(data).table.mass
    5000.0
    """
    with reading():
        return _scenario_from_dict(data, Path(base_dir), default_name)


def _scenario_from_dict(data: Mapping[str, Any], base_dir: Path, default_name: str) -> Scenario:
    top = KeyReader(data, "")
    name = top.string("name", default_name or "scenario")
    gravity = top.number("gravity", 9.81, nonnegative=True)
    table = _read_table(KeyReader(top.raw("table"), "table"), base_dir)
    read = tuple(
        _read_isolator(KeyReader(item, f"isolators[{i}]"))
        for i, item in enumerate(table_of_tables(data, "isolators"))
    )
    top.used.add("isolators")
    air, leveling = read_pneumatics(top, data, read)
    isolators = _one_kind(read)
    check_isolator_layout(isolators)
    sim_reader = KeyReader(top.raw("simulation", {}), "simulation")
    simulation = SimulationSettings(
        duration=sim_reader.number("duration", 10.0, positive=True),
        sample_rate=sim_reader.number("sample_rate", 1000.0, positive=True),
    )
    sim_reader.finish()
    sequence = read_sequence(top)
    carriages = tuple(
        _read_carriage(KeyReader(item, f"carriages[{i}]"), base_dir, sequence)
        for i, item in enumerate(table_of_tables(data, "carriages"))
    )
    top.used.add("carriages")
    check_carriage_tree(carriages)
    actuators = tuple(
        _read_actuator(KeyReader(item, f"actuators[{i}]"))
        for i, item in enumerate(table_of_tables(data, "actuators"))
    )
    top.used.add("actuators")
    check_unique_names([a.name for a in actuators], "actuators")
    settling = _read_settling(KeyReader(top.raw("settling", {}), "settling"))
    ground = _read_ground(KeyReader(top.raw("ground"), "ground"), base_dir) if top.has("ground") else None
    top.used.add("ground")
    points = tuple(
        _read_point(KeyReader(item, f"points[{i}]"))
        for i, item in enumerate(table_of_tables(data, "points"))
    )
    top.used.add("points")
    check_unique_names([pt.name for pt in points], "points")
    windows = read_windows(top, data, [pt.name for pt in points])
    sensors = read_sensors(top, data)
    disturbances = read_disturbances(top, data)
    top.finish()
    scenario = Scenario(
        name=name,
        table=table,
        isolators=isolators,
        carriages=carriages,
        actuators=actuators,
        simulation=simulation,
        settling=settling,
        gravity=gravity,
        ground=ground,
        points=points,
        air=air,
        leveling=leveling,
        windows=windows,
        sequence=sequence,
        sensors=sensors,
        disturbances=disturbances,
    )
    check_scenario_values(scenario)  # the rules the parameter vectors are checked by (isolator.scenario.rules)
    check_sequence(scenario)
    check_extent(scenario)  # positions and strokes against table.size
    check_pneumatics(scenario)
    check_flexible(scenario)  # the rigid modes against [table], everything on the top within its faces
    return scenario


def _read_table(r: KeyReader, base_dir: Path) -> Table:
    mass = r.number("mass", positive=True)
    size = r.vector("size", None, positive=True) if r.has("size") else None
    r.used.add("size")
    if r.has("inertia"):
        inertia = r.vector("inertia", positive=True)
        a, b, c = inertia
        if a + b < c * (1 - 1e-9) or a + c < b * (1 - 1e-9) or b + c < a * (1 - 1e-9):
            raise ScenarioError(
                "table.inertia: principal moments must satisfy the triangle inequality "
                f"(each <= the sum of the other two), got {list(inertia)}"
            )
    elif size is not None:
        lx, ly, lz = size
        inertia = (mass * (ly**2 + lz**2) / 12, mass * (lx**2 + lz**2) / 12, mass * (lx**2 + ly**2) / 12)
    else:
        raise ScenarioError("table: needs size (box inertia) or inertia")
    flexible = read_flexible(KeyReader(r.raw("flexible"), "table.flexible"), base_dir, mass, size) \
        if r.has("flexible") else None
    r.used.add("flexible")
    r.finish()
    return Table(mass=mass, inertia=inertia, size=size, flexible=flexible)


def _one_kind(
    isolators: tuple[Isolator | PneumaticIsolator, ...],
) -> tuple[Isolator, ...] | tuple[PneumaticIsolator, ...]:
    """The isolators as a tuple of one kind (``read_pneumatics`` has refused mixtures)."""
    springs = tuple(iso for iso in isolators if isinstance(iso, Isolator))
    return springs if len(springs) == len(isolators) else tuple(
        iso for iso in isolators if isinstance(iso, PneumaticIsolator)
    )


def _read_isolator(r: KeyReader) -> Isolator | PneumaticIsolator:
    kind = r.string("model", "spring-damper")
    if kind == "pneumatic":
        return read_pneumatic_isolator(r)
    if kind != "spring-damper":
        raise ScenarioError(f"{r.key('model')}: must be 'spring-damper' or 'pneumatic', got '{kind}'")
    iso = Isolator(
        name=r.string("name", ""),
        position=r.vector("position"),
        stiffness=r.vector("stiffness", nonnegative=True),
        damping=r.vector("damping", nonnegative=True),
    )
    r.finish()
    return iso


def _read_profile(r: KeyReader, base_dir: Path) -> Profile:
    kind = r.string("type")
    if kind == "sine":
        prof: Profile = SineProfile(
            amplitude=r.number("amplitude"),
            omega=r.number("omega", positive=True),
            phase=r.number("phase", 0.0),
            offset=r.number("offset", 0.0),
            t0=r.number("t0", 0.0, nonnegative=True),
        )
    elif kind in ("trapezoid", "scurve"):
        common = {
            "start": r.number("start"),
            "stroke": r.number("stroke"),
            "velocity": r.number("velocity", rule=MOTION),
            "acceleration": r.number("acceleration", rule=MOTION),
            "t0": r.number("t0", 0.0, nonnegative=True),
        }
        if kind == "trapezoid":
            dec = r.number("deceleration", rule=MOTION) if r.has("deceleration") else None
            r.used.add("deceleration")
            prof = trapezoid(deceleration=dec, **common)
        else:
            dec = r.number("deceleration", rule=MOTION) if r.has("deceleration") else None
            jerk_down = r.number("deceleration_jerk", rule=MOTION) if r.has("deceleration_jerk") else None
            r.used.update(("deceleration", "deceleration_jerk"))
            prof = scurve(
                jerk=r.number("jerk", rule=MOTION), deceleration=dec, deceleration_jerk=jerk_down, **common
            )
    elif kind == "samples":
        t, q = read_samples(r, base_dir)
        prof = samples(t, q)
    else:
        raise ScenarioError(
            f"{r.key('type')}: unknown profile type '{kind}' (sine, trapezoid, scurve, samples)"
        )
    r.finish()
    return prof


def _read_carriage(r: KeyReader, base_dir: Path, sequence: StepSequence | None) -> Carriage:
    name = r.string("name")
    if not name or name == "table":
        raise ScenarioError(f"{r.key('name')}: must be a non-empty name other than 'table'")
    if sequence is not None and r.has("profile"):
        raise ScenarioError(f"{r.key('profile')}: with [sequence] the carriages give no profile (the sequence's "
                            "steps move them); remove it, or remove [sequence]")
    profile = _read_profile(KeyReader(r.raw("profile"), r.key("profile")), base_dir) if sequence is None else \
        held(dict(sequence.initial).get(name, 0.0))  # held where the sequence starts it; run_sequence moves it
    carriage = Carriage(
        name=name,
        mass=r.number("mass", positive=True),
        parent=r.string("parent", "table"),
        axis=r.unit_vector("axis"),
        origin=r.vector("origin", (0.0, 0.0, 0.0)),
        profile=profile,
        limits=_read_limits(KeyReader(r.raw("limits", {}), r.key("limits"))),
        feet=read_feet(r),
    )
    r.finish()
    return carriage


def _read_limits(r: KeyReader) -> MotionLimits:
    keys = ("velocity", "acceleration", "jerk")
    values = {k: r.number(k, rule=MOTION) if r.has(k) else None for k in keys}
    r.used.update(keys)
    r.finish()
    return MotionLimits(**values)


def _read_actuator(r: KeyReader) -> Actuator:
    name = r.string("name")
    if not name:
        raise ScenarioError(f"{r.key('name')}: must be a non-empty name")
    act = Actuator(
        name=name,
        position=r.vector("position"),
        direction=r.unit_vector("direction"),
        max_force=r.number("max_force", positive=True),
        bandwidth=r.number("bandwidth", positive=True) if r.has("bandwidth") else None,
        max_rate=r.number("max_rate", positive=True) if r.has("max_rate") else None,
        noise_psd=read_density(r.raw("noise_psd"), r.key("noise_psd")) if r.has("noise_psd") else None,
    )
    r.used.update(("bandwidth", "max_rate", "noise_psd"))
    r.finish()
    return act


def _read_point(r: KeyReader) -> Point:
    name = r.string("name")
    if not name:
        raise ScenarioError(f"{r.key('name')}: must be a non-empty name")
    point = Point(name=name, position=r.vector("position"), feet=read_feet(r))
    r.finish()
    return point


def _read_ground(r: KeyReader, base_dir: Path) -> Ground:
    motion = {}
    for axis in SIGNALS:
        if r.has(axis):
            motion[axis] = _read_profile(KeyReader(r.raw(axis), r.key(axis)), base_dir)
    spectrum = None
    if r.has("spectrum"):
        spectrum = read_spectrum(KeyReader(r.raw("spectrum"), r.key("spectrum")), base_dir)
    r.used.add("spectrum")
    r.finish()
    return Ground(motion=motion, spectrum=spectrum)


def _read_settling(r: KeyReader) -> Settling:
    if r.has("fraction") and r.has("tolerance"):
        raise ScenarioError("settling: give fraction or tolerance, not both")
    if r.has("tolerance"):
        tol = r.raw("tolerance")
        if not isinstance(tol, list) or len(tol) != 2:
            raise ScenarioError("settling.tolerance: must be [translation m, rotation rad]")
        pair = tuple(number(v, f"settling.tolerance[{i}]", positive=True) for i, v in enumerate(tol))
        r.finish()
        return Settling(fraction=None, tolerance=pair)  # type: ignore[arg-type]
    fraction = r.number("fraction", 0.05, positive=True, below=1.0)
    r.finish()
    return Settling(fraction=fraction)


register_conversion(Scenario, load_scenario)
register_field_checks()
check_public(globals(), ("load_scenario", "scenario_from_dict"))
