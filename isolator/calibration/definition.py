"""A calibration file read key by key (``docs/scenario-format.md``, "Calibration from measured records"):
the scenario, the parameters to fit with their bounds, the sensors, the experiments.

Every problem is one :class:`~isolator.errors.ScenarioError` naming the file and the key.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from isolator.errors import ParameterError, ScenarioError
from isolator.model.parameters import ParameterLayout
from isolator.scenario.definitions import Scenario
from isolator.scenario.keys import KeyReader, load_toml, number, table_of_tables
from isolator.scenario.reader import load_scenario, resolve_scenario_path
from isolator.scenario.rules import closest
from isolator.scenario.sensors import read_sensors
from isolator.sweep.names import resolve

__all__ = ["DEFAULT_BAND", "KINDS", "Calibration", "Experiment", "FitParameter", "bundled_calibrations",
           "calibration_from_dict", "load_calibration"]

#: what an experiment records: the floor moving with the carriages parked, or the carriages moving
KINDS = ("floor", "move")
#: the band a floor experiment fits by default [Hz]
DEFAULT_BAND = (0.5, 50.0)
#: the default bounds: this factor below and above the scenario's value
BOUND_FACTOR = 10.0
_KEYS = ("scenario", "fit", "bounds", "sensors", "experiments")


@dataclass(frozen=True)
class FitParameter:
    """One fitted name and the parameter entries it sets (one value shared by every entry).

    Attributes
    ----------
    name : str
        As the calibration file gives it (``isolators[*].stiffness.z``).
    entries : tuple of int
        Indices into the parameter vector (``ParameterLayout.names``).
    initial : float
        The scenario's value [SI], where the fit starts.
    bounds : tuple of float
        [SI]; the fit stays inside them.
    """

    name: str
    entries: tuple[int, ...]
    initial: float
    bounds: tuple[float, float]


@dataclass(frozen=True)
class Experiment:
    """One record and how it was taken.

    Attributes
    ----------
    name : str
    file : Path
        The record (CSV, or UFF58 with a ``.uff``/``.unv`` suffix).
    kind : {"floor", "move"}
    frequency : tuple of float
        The band a floor experiment fits [Hz].
    segment : float or None
        Welch segment [s] of a floor experiment (None: from the lowest mode).
    positions : mapping of str to float
        Where the carriages are parked in a floor experiment [m] (the others at their start).
    """

    name: str
    file: Path
    kind: str
    frequency: tuple[float, float] = DEFAULT_BAND
    segment: float | None = None
    positions: Mapping[str, float] = field(default_factory=dict)

    @property
    def key(self) -> str:
        """How messages name it: ``experiments['floor-random']``."""
        return f"experiments[{self.name!r}]"


@dataclass(frozen=True)
class Calibration:
    """A calibration: the scenario (with the calibration's own sensors added), what to fit, the records.

    Attributes
    ----------
    scenario : Scenario
        The scenario to calibrate, its ``sensors`` the scenario's then the calibration file's.
    scenario_file : Path
        Where the scenario was read from (the fitted scenario is this file with the fitted values).
    parameters : tuple of FitParameter
    experiments : tuple of Experiment
    path : Path or None
        The calibration file (None when built in Python).
    """

    scenario: Scenario
    scenario_file: Path
    parameters: tuple[FitParameter, ...]
    experiments: tuple[Experiment, ...]
    path: Path | None = None

    @property
    def layout(self) -> ParameterLayout:
        """The scenario's parameter layout."""
        return ParameterLayout.of(self.scenario)

    @property
    def names(self) -> tuple[str, ...]:
        """The fitted names, in order."""
        return tuple(f.name for f in self.parameters)

    def vector(self, values: np.ndarray | None = None) -> np.ndarray:
        """The scenario's parameter vector with each fitted name set to ``values`` [SI] (default: initial)."""
        layout = self.layout
        p = layout.pack(self.scenario).copy()
        if values is not None:
            for f, v in zip(self.parameters, values, strict=True):
                p[list(f.entries)] = v
        return p

    @property
    def initial(self) -> np.ndarray:
        """The fitted names' initial values [SI]."""
        return np.array([f.initial for f in self.parameters])


#: where the bundled calibrations live (one folder each: calibration.toml, the scenario, the records)
BUNDLED = Path(__file__).resolve().parents[1] / "data" / "calibrations"


def bundled_calibrations() -> dict[str, Path]:
    """The bundled calibrations' files by name (``table-3-2``: SYNTHETIC records of the paper's table whose
    isolators are 15-30 % off the datasheet, made by the MuJoCo check)."""
    return {p.parent.name: p for p in sorted(BUNDLED.glob("*/calibration.toml"))}


def load_calibration(path: str | Path) -> Calibration:
    """Read a calibration file (TOML; every problem a :class:`ScenarioError` naming the file and the key), or a
    bundled calibration by name (:func:`bundled_calibrations`)."""
    path = Path(path)
    bundled = bundled_calibrations()
    if not path.exists() and str(path) in bundled:
        path = bundled[str(path)]
    if not path.exists():
        raise ScenarioError(f"{path}: no such calibration file (bundled: {', '.join(bundled) or 'none'})")
    data = load_toml(path, "calibration file")
    try:
        return calibration_from_dict(data, path.parent, path)
    except ScenarioError as exc:
        raise ScenarioError(f"{path}: {exc}") from None


def calibration_from_dict(data: Mapping[str, Any], base_dir: Path | str = ".", path: Path | None = None
                          ) -> Calibration:
    """A calibration from its keys (as ``tomllib`` gives them); relative files are read from ``base_dir``."""
    base = Path(base_dir)
    top = KeyReader(data, "")
    for key in data:
        if key not in _KEYS:
            near = closest(str(key), _KEYS)
            hint = f"; did you mean '{near}'?" if near else f" (allowed: {', '.join(_KEYS)})"
            raise ScenarioError(f"{key}: unknown key{hint}")
    source = top.string("scenario")
    scenario_file = base / source if (base / source).is_file() else resolve_scenario_path(source)
    try:
        scenario = load_scenario(scenario_file)
    except ScenarioError as exc:
        raise ScenarioError(f"scenario ({scenario_file}): {exc}") from None
    sensors = read_sensors(top, data, "sensors", scenario.sensors)
    scenario = replace(scenario, sensors=scenario.sensors + sensors)
    parameters = _fit_parameters(top, scenario)
    experiments = tuple(_experiment(KeyReader(item, f"experiments[{i}]"), base, scenario)
                        for i, item in enumerate(table_of_tables(data, "experiments")))
    top.used.add("experiments")
    if not experiments:
        raise ScenarioError("experiments: a calibration needs at least one [[experiments]] block")
    names = [e.name for e in experiments]
    for i, n in enumerate(names):
        if n in names[:i]:
            raise ScenarioError(f"experiments[{i}].name: '{n}' is used twice")
    top.finish()
    return Calibration(scenario, scenario_file, parameters, experiments, path)


def _fit_parameters(top: KeyReader, scenario: Scenario) -> tuple[FitParameter, ...]:
    fit = top.raw("fit")
    if not isinstance(fit, list) or not fit or not all(isinstance(n, str) for n in fit):
        raise ScenarioError("fit: must be a non-empty list of parameter names (as `isolator sweep --set` takes them)")
    layout = ParameterLayout.of(scenario)
    p = layout.pack(scenario)
    bounds = top.raw("bounds", {})
    if not isinstance(bounds, Mapping):
        raise ScenarioError("bounds: must be a table of [low, high] by fitted name")
    for name in bounds:
        if name not in fit:
            raise ScenarioError(f"bounds.{name}: not a fitted name (fit: {', '.join(fit)})")
    out: list[FitParameter] = []
    taken: dict[int, str] = {}
    for i, name in enumerate(fit):
        try:
            entries = resolve(layout, name, "set").entries
        except ParameterError as exc:
            raise ScenarioError(f"fit[{i}]: {str(exc).split(': ', 1)[1]}") from None
        for e in entries:
            if e in taken:
                raise ScenarioError(f"fit[{i}]: '{name}' sets {layout.names[e]}, which '{taken[e]}' fits already")
            taken[e] = name
        values = p[list(entries)]
        initial = float(values[0])
        if np.any(np.abs(values - initial) > 1e-12 * abs(initial)):
            raise ScenarioError(f"fit[{i}]: '{name}' would share one value among entries the scenario gives "
                                f"different values ({', '.join(f'{v:.6g}' for v in values)}); fit each by its index")
        if not initial > 0:
            raise ScenarioError(f"fit[{i}]: '{name}' is {initial:g} in the scenario; a fitted parameter must be "
                                "positive (the fit is in its logarithm)")
        low, high = initial / BOUND_FACTOR, initial * BOUND_FACTOR
        if name in bounds:
            low, high = _bounds(bounds[name], f"bounds.{name}", initial)
        out.append(FitParameter(name, tuple(entries), initial, (low, high)))
    return tuple(out)


def _bounds(value: Any, key: str, initial: float) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2:
        raise ScenarioError(f"{key}: must be [low, high]")
    low, high = (number(v, f"{key}[{j}]", positive=True) for j, v in enumerate(value))
    if not low < high:
        raise ScenarioError(f"{key}: low {low:g} must be below high {high:g}")
    if not low <= initial <= high:
        raise ScenarioError(f"{key}: [{low:g}, {high:g}] must contain the scenario's value {initial:g} "
                            "(the fit starts there)")
    return low, high


def _experiment(r: KeyReader, base: Path, scenario: Scenario) -> Experiment:
    name = r.string("name")
    if not name.strip():
        raise ScenarioError(f"{r.key('name')}: must be a non-empty name")
    file = base / r.string("file")
    kind = r.string("kind")
    if kind not in KINDS:
        raise ScenarioError(f"{r.key('kind')}: must be \"floor\" or \"move\", got {kind!r}")
    if kind == "move":
        for key in ("frequency", "segment", "positions"):
            if r.has(key):
                raise ScenarioError(f"{r.key(key)}: only a \"floor\" experiment takes it (a \"move\" experiment is "
                                    "compared sample by sample, with the carriages moving as the scenario says)")
        r.finish()
        return Experiment(name, file, kind)
    band = DEFAULT_BAND
    if r.has("frequency"):
        raw = r.raw("frequency")
        if not isinstance(raw, list) or len(raw) != 2:
            raise ScenarioError(f"{r.key('frequency')}: must be [low, high] in Hz")
        band = (number(raw[0], f"{r.key('frequency')}[0]", positive=True),
                number(raw[1], f"{r.key('frequency')}[1]", positive=True))
        if not band[0] < band[1]:
            raise ScenarioError(f"{r.key('frequency')}: low {band[0]:g} Hz must be below high {band[1]:g} Hz")
    r.used.add("frequency")
    segment = r.number("segment", positive=True) if r.has("segment") else None
    r.used.add("segment")
    positions: dict[str, float] = {}
    raw_positions = r.raw("positions", {})
    if not isinstance(raw_positions, Mapping):
        raise ScenarioError(f"{r.key('positions')}: must be a table of carriage positions [m] by name")
    carriages = [c.name for c in scenario.carriages]
    for carriage, value in raw_positions.items():
        if carriage not in carriages:
            near = closest(str(carriage), carriages)
            hint = f"; did you mean '{near}'?" if near else f" (carriages: {', '.join(carriages) or 'none'})"
            raise ScenarioError(f"{r.key('positions')}.{carriage}: no such carriage{hint}")
        positions[carriage] = number(value, f"{r.key('positions')}.{carriage}")
    r.finish()
    return Experiment(name, file, kind, band, segment, positions)
