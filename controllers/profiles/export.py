"""An optimised design written back as a scenario file that loads and simulates as is."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from isolator.scenario.arguments import check_public
from isolator.scenario.reader import resolve_scenario_path

from .move_design import MoveDesign

__all__ = ["absolute_files", "write_scenario", "write_scenario_profiles"]


def write_scenario(source: str | Path | None, designs: Sequence[MoveDesign], path: str | Path) -> Path:
    """Write a scenario file: the source file with each designed carriage's profile replaced.

    Parameters
    ----------
    source : str or Path or None
        The scenario file (or bundled name) the designs were made for.
    designs : sequence of MoveDesign
        Per carriage, by name.
    path : str or Path
        The file to write; it loads with :func:`isolator.load_scenario`.
        Relative ``file`` keys of the source are made absolute.
    """
    import tomllib

    import tomli_w

    origin = resolve_scenario_path(source)
    with open(origin, "rb") as handle:
        data = tomllib.load(handle)
    absolute_files(data, origin.parent)
    by_name = {d.name: d for d in designs}
    for carriage in data.get("carriages", []):
        if carriage.get("name") in by_name:
            carriage["profile"] = by_name[carriage["name"]].profile().settings
    data["name"] = f"{data.get('name', origin.stem)}-optimised"
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    with open(target, "wb") as handle:
        tomli_w.dump(data, handle)
    return target


def write_scenario_profiles(source: str | Path | None, scenario: Any, path: str | Path, name: str) -> Path | None:
    """Write the source scenario file with every carriage's profile taken from ``scenario`` (same carriages,
    by name) under the name ``name``; None (nothing written) when a profile has no scenario-file keys (an
    input-shaped or time-optimal profile is a piecewise polynomial)."""
    profiles = {}
    for carriage in scenario.carriages:
        try:
            profiles[carriage.name] = carriage.profile.settings
        except (AttributeError, ValueError):
            return None
    import tomllib

    import tomli_w

    origin = resolve_scenario_path(source)
    with open(origin, "rb") as handle:
        data = tomllib.load(handle)
    absolute_files(data, origin.parent)
    for carriage in data.get("carriages", []):
        if carriage.get("name") in profiles:
            carriage["profile"] = profiles[carriage["name"]]
    data["name"] = name
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    with open(target, "wb") as handle:
        tomli_w.dump(data, handle)
    return target


def absolute_files(data: Any, base: Path) -> None:
    """Make every relative ``file`` key under ``data`` absolute (relative to ``base``)."""
    if isinstance(data, dict):
        for key, value in data.items():
            if key == "file" and isinstance(value, str) and not Path(value).is_absolute():
                data[key] = str((base / value).resolve())
            else:
                absolute_files(value, base)
    elif isinstance(data, list):
        for item in data:
            absolute_files(item, base)


check_public(globals())
