"""Reading ``[[windows]]`` (absolute settling windows at points, ``docs/scenario-format.md``); ``[sequence]``
is read by :mod:`isolator.scenario.sequence`."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from isolator.errors import ScenarioError
from isolator.scenario.keys import KeyReader, number, table_of_tables
from isolator.scenario.windows import WINDOW_AXES, Window, check_windows

__all__ = ["read_windows"]


def read_windows(top: KeyReader, data: Mapping[str, Any], point_names: Sequence[str]) -> tuple[Window, ...]:
    """The ``[[windows]]`` blocks, checked against the ``[[points]]`` names."""
    top.used.add("windows")
    windows = tuple(_read_window(KeyReader(item, f"windows[{i}]"))
                    for i, item in enumerate(table_of_tables(data, "windows")))
    check_windows(windows, point_names)
    return windows


def _read_window(r: KeyReader) -> Window:
    point = r.string("point")
    translation = number(r.raw("translation"), r.key("translation"), positive=True)
    axes = r.raw("axes", list(WINDOW_AXES))
    if not isinstance(axes, list) or not all(isinstance(a, str) for a in axes):
        raise ScenarioError(f"{r.key('axes')}: must be a list of axis names among \"x\", \"y\", \"z\"")
    random = number(r.raw("random"), r.key("random"), positive=True) if r.has("random") else None
    r.used.add("random")
    r.finish()
    return Window(point=point, translation=translation, axes=tuple(axes), random=random)
