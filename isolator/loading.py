"""Reading and validating scenario files (TOML) into :class:`Scenario` objects.

Every problem is reported as one :class:`ScenarioError` whose message starts
with the key path, for example ``carriages[1].profile.acceleration: must be > 0``.
"""

from __future__ import annotations

import csv
import math
import tomllib
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from . import profiles
from .errors import ScenarioError
from .scenario import (
    SIGNALS,
    Actuator,
    Carriage,
    FloorSpectrum,
    Ground,
    Isolator,
    MotionLimits,
    Point,
    Scenario,
    Settling,
    SimulationSettings,
    Table,
)

__all__ = [
    "bundled_scenarios",
    "load_scenario",
    "load_spectrum",
    "read_csv_columns",
    "resolve_scenario_path",
    "scenario_from_dict",
]

DEFAULT_SCENARIO = "paper-table-3-2"
_UNIT_TOL = 1e-6


def bundled_scenarios() -> dict[str, Path]:
    """The scenarios shipped with the package, by name."""
    folder = resources.files("isolator") / "data" / "scenarios"
    return {
        Path(str(entry)).stem: Path(str(entry))
        for entry in folder.iterdir()
        if str(entry).endswith(".toml")
    }


def resolve_scenario_path(spec: str | Path | None) -> Path:
    """A scenario file path from a path or a bundled scenario's name (None: the default)."""
    if spec is None:
        spec = DEFAULT_SCENARIO
    path = Path(spec)
    if path.is_file():
        return path
    bundled = bundled_scenarios()
    name = path.name[:-5] if path.name.endswith(".toml") else path.name
    if name in bundled and not path.exists():
        return bundled[name]
    known = ", ".join(sorted(bundled))
    raise ScenarioError(f"{spec}: no such scenario file (bundled scenarios: {known})")


def load_scenario(spec: str | Path | None = None) -> Scenario:
    """Read and validate a scenario.

    Parameters
    ----------
    spec : str or Path or None
        A TOML file, or the name of a bundled scenario (``paper-table-3-1``,
        ``paper-table-3-2``); None loads ``paper-table-3-2``.

    Returns
    -------
    Scenario

    Raises
    ------
    ScenarioError
        With the offending key path and the reason.
    """
    path = resolve_scenario_path(spec)
    try:
        with open(path, "rb") as handle:
            data = tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{path}: not valid TOML ({exc})") from None
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot be read ({exc.strerror})") from None
    return scenario_from_dict(data, base_dir=path.parent, default_name=path.stem)


class _Reader:
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
        return _number(value, self.key(name), positive=positive, nonnegative=nonnegative, below=below)

    def vector(self, name: str, default: Any = ..., *, positive: bool = False, nonnegative: bool = False):
        value = self.raw(name, default)
        key = self.key(name)
        if not isinstance(value, list | tuple) or len(value) != 3:
            raise ScenarioError(f"{key}: must be a list of three numbers")
        return tuple(
            _number(v, f"{key}[{i}]", positive=positive, nonnegative=nonnegative)
            for i, v in enumerate(value)
        )

    def unit_vector(self, name: str):
        vec = self.vector(name)
        norm = math.sqrt(sum(v * v for v in vec))
        if norm == 0.0:
            raise ScenarioError(f"{self.key(name)}: must be a unit vector, got zero length")
        if abs(norm - 1.0) > _UNIT_TOL:
            raise ScenarioError(f"{self.key(name)}: must be a unit vector, got length {norm:.6g}")
        return tuple(v / norm for v in vec)

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


def _number(
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


def _table_of_tables(data: Mapping, name: str) -> list:
    value = data.get(name, [])
    if not isinstance(value, list):
        raise ScenarioError(f"{name}: must be an array of tables ([[{name}]])")
    return value


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
    """
    base_dir = Path(base_dir)
    top = _Reader(data, "")
    name = top.string("name", default_name)
    gravity = top.number("gravity", 9.81, nonnegative=True)
    table = _read_table(_Reader(top.raw("table"), "table"))
    isolators = tuple(
        _read_isolator(_Reader(item, f"isolators[{i}]"))
        for i, item in enumerate(_table_of_tables(data, "isolators"))
    )
    top.used.add("isolators")
    _check_isolator_layout(isolators)
    sim_reader = _Reader(top.raw("simulation", {}), "simulation")
    simulation = SimulationSettings(
        duration=sim_reader.number("duration", 10.0, positive=True),
        sample_rate=sim_reader.number("sample_rate", 1000.0, positive=True),
    )
    sim_reader.finish()
    carriages = tuple(
        _read_carriage(_Reader(item, f"carriages[{i}]"), base_dir)
        for i, item in enumerate(_table_of_tables(data, "carriages"))
    )
    top.used.add("carriages")
    _check_carriage_tree(carriages)
    actuators = tuple(
        _read_actuator(_Reader(item, f"actuators[{i}]"))
        for i, item in enumerate(_table_of_tables(data, "actuators"))
    )
    top.used.add("actuators")
    _check_unique_names([a.name for a in actuators], "actuators")
    settling = _read_settling(_Reader(top.raw("settling", {}), "settling"))
    ground = _read_ground(_Reader(top.raw("ground"), "ground"), base_dir) if top.has("ground") else None
    top.used.add("ground")
    points = tuple(
        _read_point(_Reader(item, f"points[{i}]"))
        for i, item in enumerate(_table_of_tables(data, "points"))
    )
    top.used.add("points")
    _check_unique_names([pt.name for pt in points], "points")
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
    )
    _check_strokes(scenario)
    return scenario


def _read_table(r: _Reader) -> Table:
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
    r.finish()
    return Table(mass=mass, inertia=inertia, size=size)


def _read_isolator(r: _Reader) -> Isolator:
    iso = Isolator(
        name=r.string("name", ""),
        position=r.vector("position"),
        stiffness=r.vector("stiffness", nonnegative=True),
        damping=r.vector("damping", nonnegative=True),
    )
    r.finish()
    return iso


def _check_isolator_layout(isolators: tuple[Isolator, ...]) -> None:
    if len(isolators) < 3:
        raise ScenarioError(f"isolators: need at least three, got {len(isolators)}")
    pts = np.array([iso.position for iso in isolators])
    span = np.linalg.svd(pts - pts.mean(axis=0), compute_uv=False)
    scale = max(float(np.abs(pts).max()), 1e-12)
    if span[1] <= 1e-9 * scale:
        raise ScenarioError("isolators: positions all lie on one line; the table could roll about it")


def _read_profile(r: _Reader, base_dir: Path) -> profiles.Profile:
    kind = r.string("type")
    if kind == "sine":
        prof: profiles.Profile = profiles.SineProfile(
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
            "velocity": r.number("velocity", positive=True),
            "acceleration": r.number("acceleration", positive=True),
            "t0": r.number("t0", 0.0, nonnegative=True),
        }
        if kind == "trapezoid":
            dec = r.number("deceleration", positive=True) if r.has("deceleration") else None
            r.used.add("deceleration")
            prof = profiles.trapezoid(deceleration=dec, **common)
        else:
            dec = r.number("deceleration", positive=True) if r.has("deceleration") else None
            jerk_down = r.number("deceleration_jerk", positive=True) if r.has("deceleration_jerk") else None
            r.used.update(("deceleration", "deceleration_jerk"))
            prof = profiles.scurve(
                jerk=r.number("jerk", positive=True), deceleration=dec, deceleration_jerk=jerk_down, **common
            )
    elif kind == "samples":
        t, q = _read_samples(r, base_dir)
        prof = profiles.samples(t, q)
    else:
        raise ScenarioError(
            f"{r.key('type')}: unknown profile type '{kind}' (sine, trapezoid, scurve, samples)"
        )
    r.finish()
    return prof


def read_csv_columns(
    path: Path, key: str, required: tuple[str, ...], optional: tuple[str, ...] = (), exact: bool = False
) -> dict[str, np.ndarray]:
    """Numeric columns of a CSV file with a header line, checked.

    Parameters
    ----------
    path : Path
        The file.
    key : str
        Key path named in errors.
    required, optional : tuple of str
        Column names that must and may appear.
    exact : bool
        The header must be exactly ``required`` in that order.

    Raises
    ------
    ScenarioError
        Unreadable file, unknown or missing columns, a cell that is not a number.
    """
    try:
        with open(path, newline="") as handle:
            rows = list(csv.reader(handle))
    except OSError as exc:
        raise ScenarioError(f"{key}: cannot read '{path}' ({exc.strerror})") from None
    header = [h.strip() for h in rows[0]] if rows else []
    if exact and header != list(required):
        raise ScenarioError(f"{key}: '{path}' must be a CSV with the header '{','.join(required)}'")
    missing = [c for c in required if c not in header]
    unknown = [c for c in header if c not in required + optional]
    if missing or unknown or len(set(header)) != len(header):
        allowed = ", ".join(required + optional)
        raise ScenarioError(
            f"{key}: '{path}' must be a CSV whose header has {', '.join(required)} and maybe "
            f"other columns among ({allowed}), once each; got '{','.join(header)}'"
        )
    values = []
    for line, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        if len(row) != len(header):
            raise ScenarioError(f"{key}: '{path}' line {line}: needs {len(header)} values ({','.join(header)})")
        try:
            values.append([float(x) for x in row])
        except ValueError:
            raise ScenarioError(f"{key}: '{path}' line {line}: not all numbers") from None
    arr = np.array(values, dtype=float).reshape(-1, len(header))
    return {name: arr[:, i] for i, name in enumerate(header)}


def _read_samples(r: _Reader, base_dir: Path) -> tuple[np.ndarray, np.ndarray]:
    if r.has("file"):
        if r.has("t") or r.has("q"):
            raise ScenarioError(f"{r.key('file')}: give either file or inline t and q, not both")
        file_key = r.key("file")
        columns = read_csv_columns(base_dir / r.string("file"), file_key, ("t", "q"), exact=True)
        t, q, key = columns["t"], columns["q"], file_key
    else:
        tk, qk = r.key("t"), r.key("q")
        t_raw, q_raw = r.raw("t"), r.raw("q")
        for k, v in ((tk, t_raw), (qk, q_raw)):
            if not isinstance(v, list) or not all(
                isinstance(x, int | float) and not isinstance(x, bool) for x in v
            ):
                raise ScenarioError(f"{k}: must be a list of numbers")
        t, q, key = np.array(t_raw, float), np.array(q_raw, float), tk
        if len(t) != len(q):
            raise ScenarioError(f"{qk}: has {len(q)} values but t has {len(t)}")
    r.used.update({"file", "t", "q"})
    if len(t) < 2:
        raise ScenarioError(f"{key}: needs at least two samples")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q))):
        raise ScenarioError(f"{key}: samples must be finite (found NaN or infinity)")
    if np.any(np.diff(t) <= 0):
        raise ScenarioError(f"{key}: sample times must be strictly increasing")
    if t[0] < 0:
        raise ScenarioError(f"{key}: sample times must be >= 0, got {t[0]:g}")
    return t, q


def _read_carriage(r: _Reader, base_dir: Path) -> Carriage:
    name = r.string("name")
    if not name or name == "table":
        raise ScenarioError(f"{r.key('name')}: must be a non-empty name other than 'table'")
    carriage = Carriage(
        name=name,
        mass=r.number("mass", positive=True),
        parent=r.string("parent", "table"),
        axis=r.unit_vector("axis"),
        origin=r.vector("origin", (0.0, 0.0, 0.0)),
        profile=_read_profile(_Reader(r.raw("profile"), r.key("profile")), base_dir),
        limits=_read_limits(_Reader(r.raw("limits", {}), r.key("limits"))),
    )
    r.finish()
    return carriage


def _read_limits(r: _Reader) -> MotionLimits:
    keys = ("velocity", "acceleration", "jerk")
    values = {k: r.number(k, positive=True) if r.has(k) else None for k in keys}
    r.used.update(keys)
    r.finish()
    return MotionLimits(**values)


def _check_unique_names(names: list[str], section: str) -> None:
    """Each name once per section, else an error naming the second use."""
    for i, n in enumerate(names):
        if n in names[:i]:
            raise ScenarioError(f"{section}[{i}].name: '{n}' is used twice")


def _check_carriage_tree(carriages: tuple[Carriage, ...]) -> None:
    names = [c.name for c in carriages]
    _check_unique_names(names, "carriages")
    for i, c in enumerate(carriages):
        if c.parent == c.name:
            raise ScenarioError(f"carriages[{i}].parent: a carriage cannot be its own parent")
        if c.parent != "table" and c.parent not in names:
            raise ScenarioError(
                f"carriages[{i}].parent: unknown parent '{c.parent}' (use 'table' or a carriage name)"
            )
    parent = {c.name: c.parent for c in carriages}
    for i, c in enumerate(carriages):
        seen = [c.name]
        p = c.parent
        while p != "table":
            if p in seen:
                chain = " -> ".join([*seen, p])
                raise ScenarioError(f"carriages[{i}].parent: cyclic parents ({chain})")
            seen.append(p)
            p = parent[p]


def _read_actuator(r: _Reader) -> Actuator:
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
    )
    r.used.update(("bandwidth", "max_rate"))
    r.finish()
    return act


def _read_point(r: _Reader) -> Point:
    name = r.string("name")
    if not name:
        raise ScenarioError(f"{r.key('name')}: must be a non-empty name")
    point = Point(name=name, position=r.vector("position"))
    r.finish()
    return point


def _read_ground(r: _Reader, base_dir: Path) -> Ground:
    motion = {}
    for axis in SIGNALS:
        if r.has(axis):
            motion[axis] = _read_profile(_Reader(r.raw(axis), r.key(axis)), base_dir)
    spectrum = None
    if r.has("spectrum"):
        spectrum = _read_spectrum(_Reader(r.raw("spectrum"), r.key("spectrum")), base_dir)
    r.used.add("spectrum")
    r.finish()
    return Ground(motion=motion, spectrum=spectrum)


SPECTRUM_KINDS = ("third-octave", "psd")


def _read_spectrum(r: _Reader, base_dir: Path) -> FloorSpectrum:
    kind = r.string("kind")
    if kind not in SPECTRUM_KINDS:
        raise ScenarioError(f"{r.key('kind')}: must be one of {', '.join(SPECTRUM_KINDS)}, got '{kind}'")
    if r.has("file"):
        if any(r.has(k) for k in ("frequency", "x", "y", "z")):
            raise ScenarioError(f"{r.key('file')}: give either file or inline frequency and values, not both")
        spectrum = load_spectrum(base_dir / r.string("file"), kind, key=r.key("file"))
    else:
        columns = {"frequency": np.array(_number_list(r, "frequency"))}
        for axis in ("x", "y", "z"):
            if r.has(axis):
                columns[axis] = np.array(_number_list(r, axis))
        spectrum = _spectrum_from_columns(columns, kind, r.path)
    r.used.update({"file", "frequency", "x", "y", "z"})
    r.finish()
    return spectrum


def _number_list(r: _Reader, name: str) -> list[float]:
    value = r.raw(name)
    if not isinstance(value, list) or not value:
        raise ScenarioError(f"{r.key(name)}: must be a non-empty list of numbers")
    return [_number(v, f"{r.key(name)}[{i}]") for i, v in enumerate(value)]


def load_spectrum(path: str | Path, kind: str, key: str = "spectrum") -> FloorSpectrum:
    """Read a floor vibration spectrum from a CSV file.

    Parameters
    ----------
    path : path
        CSV with a column ``frequency_hz`` and one or more of ``x, y, z``: RMS
        velocity per one-third-octave band [m/s] (``kind="third-octave"``, at the
        band centres) or velocity PSD [(m/s)^2/Hz] (``kind="psd"``).
    kind : {"third-octave", "psd"}
    key : str
        Key path named in errors.

    Raises
    ------
    ScenarioError
        A missing file, bad columns, non-increasing frequencies, negative values.
    """
    if kind not in SPECTRUM_KINDS:
        raise ScenarioError(f"{key}: kind must be one of {', '.join(SPECTRUM_KINDS)}, got '{kind}'")
    columns = read_csv_columns(Path(path), key, ("frequency_hz",), ("x", "y", "z"))
    columns["frequency"] = columns.pop("frequency_hz")
    return _spectrum_from_columns(columns, kind, key)


def _spectrum_from_columns(columns: dict[str, np.ndarray], kind: str, key: str) -> FloorSpectrum:
    f = columns.pop("frequency")
    if not columns:
        raise ScenarioError(f"{key}: needs values for at least one of x, y, z")
    if f.size < 2 or np.any(np.diff(f) <= 0) or f[0] <= 0:
        raise ScenarioError(f"{key}: frequencies must be > 0 and strictly increasing (at least two)")
    for axis, v in columns.items():
        if v.size != f.size:
            raise ScenarioError(f"{key}.{axis}: has {v.size} values for {f.size} frequencies")
        if not np.all(np.isfinite(v)) or np.any(v < 0):
            raise ScenarioError(f"{key}.{axis}: values must be finite and >= 0")
    return FloorSpectrum(kind=kind, frequency=f, values=columns)


def _read_settling(r: _Reader) -> Settling:
    if r.has("fraction") and r.has("tolerance"):
        raise ScenarioError("settling: give fraction or tolerance, not both")
    if r.has("tolerance"):
        tol = r.raw("tolerance")
        if not isinstance(tol, list) or len(tol) != 2:
            raise ScenarioError("settling.tolerance: must be [translation m, rotation rad]")
        pair = tuple(_number(v, f"settling.tolerance[{i}]", positive=True) for i, v in enumerate(tol))
        r.finish()
        return Settling(fraction=None, tolerance=pair)  # type: ignore[arg-type]
    fraction = r.number("fraction", 0.05, positive=True, below=1.0)
    r.finish()
    return Settling(fraction=fraction)


def _check_strokes(scenario: Scenario) -> None:
    """Every carriage's mass must stay above the table's footprint (when its size is known)."""
    if scenario.table.size is None or not scenario.carriages:
        return
    t_end = scenario.simulation.duration
    if math.isfinite(scenario.stop_time):
        t_end = max(t_end, scenario.stop_time)
    times = np.linspace(0.0, t_end, 4001)
    extra = [b for b in scenario.breakpoints if 0.0 <= b <= t_end]
    times = np.union1d(times, extra)
    q = np.array([c.profile.evaluate(times)[0] for c in scenario.carriages])
    excess = scenario.outside_footprint(q)
    if excess is not None:
        i, axis, k, coordinate = excess
        half = scenario.table.size[axis] / 2.0
        which = "half-length" if axis == 0 else "half-width"
        raise ScenarioError(
            f"carriages[{i}].profile: the carriage's mass reaches {'xy'[axis]} = "
            f"{coordinate:.4g} m at t = {times[k]:.4g} s, beyond the table's "
            f"{which} {half:.4g} m (table.size)"
        )
