"""The scenarios shipped with the package (``isolator/data/scenarios``) and a scenario's file from a path or
a bundled scenario's name."""

from __future__ import annotations

import difflib
from importlib import resources
from pathlib import Path

from isolator.errors import ScenarioError
from isolator.scenario.arguments import check_public

__all__ = ["DEFAULT_SCENARIO", "bundled_scenarios", "resolve_scenario_path"]

DEFAULT_SCENARIO = "paper-table-3-2"


def bundled_scenarios() -> dict[str, Path]:
    """The scenarios shipped with the package, by name.

    Returns
    -------
    dict of str to Path
        Each bundled scenario's TOML file by its name (as :func:`load_scenario` takes it).

    Examples
    --------
    >>> from isolator import bundled_scenarios
    >>> sorted(bundled_scenarios())[:2]
    ['paper-table-3-1', 'paper-table-3-2']
    """
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
    if path.exists() and not path.is_dir():  # a FIFO or a device too: load_toml refuses it, naming what it is
        return path
    if path.is_dir():
        raise ScenarioError(f"{spec}: is a folder, not a scenario file")
    bundled = bundled_scenarios()
    name = path.name[:-5] if path.name.endswith(".toml") else path.name
    if name in bundled and not path.exists():
        return bundled[name]
    close = difflib.get_close_matches(name, sorted(bundled), n=1, cutoff=0.8)
    hint = f"did you mean '{close[0]}'? " if close else ""
    raise ScenarioError(f"{spec}: no such scenario file ({hint}bundled scenarios: {', '.join(sorted(bundled))})")


check_public(globals(), ("bundled_scenarios",))
