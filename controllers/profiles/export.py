"""An optimised design written back as a scenario file that loads and simulates as is."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from isolator.scenario.arguments import check_public
from isolator.scenario.writing import scenario_data, write_toml

from .move_design import MoveDesign

__all__ = ["write_scenario", "write_scenario_profiles"]


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

    Returns
    -------
    Path
        The file written.
    """
    origin, data = scenario_data(source)
    by_name = {d.name: d for d in designs}
    for carriage in data.get("carriages", []):
        if carriage.get("name") in by_name:
            carriage["profile"] = by_name[carriage["name"]].profile().settings
    data["name"] = f"{data.get('name', origin.stem)}-optimised"
    return write_toml(data, path)


def write_scenario_profiles(source: str | Path | None, scenario: Any, path: str | Path, name: str) -> Path | None:
    """Write the source scenario file with every carriage's profile taken from ``scenario`` (same carriages,
    by name) under the name ``name``; None (nothing written) when a profile has no scenario-file keys (an
    input-shaped or time-optimal profile is a piecewise polynomial).

    Parameters
    ----------
    source : str or Path or None
        The scenario file (or bundled name; None the default) to copy.
    scenario : Scenario
        The scenario whose carriages' profiles are written (same carriages, by name).
    path : str or Path
        The file to write.
    name : str
        The written scenario's ``name``.

    Returns
    -------
    Path or None
        The file written, or None when a profile has no scenario-file keys.
    """
    profiles = {}
    for carriage in scenario.carriages:
        try:
            profiles[carriage.name] = carriage.profile.settings
        except (AttributeError, ValueError):
            return None
    _, data = scenario_data(source)
    for carriage in data.get("carriages", []):
        if carriage.get("name") in profiles:
            carriage["profile"] = profiles[carriage["name"]]
    data["name"] = name
    return write_toml(data, path)


check_public(globals())
