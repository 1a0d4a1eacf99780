"""``[table.flexible]`` and the ``feet`` of points and carriages read from a scenario's keys, and the same built
in Python (:func:`load_flexible`)."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.flexible.definitions import FlexibleTop
from isolator.scenario.flexible.modal_file import load_modal_data
from isolator.scenario.flexible.rigid_check import check_rigid
from isolator.scenario.keys import KeyReader, number

__all__ = ["Feet", "as_feet", "check_top", "flexible_values", "load_flexible", "read_feet", "read_flexible",
           "tupled_feet"]

#: the feet of a point or carriage: (x, y) offsets [m]
Feet = tuple[tuple[float, float], ...]


def load_flexible(
    modes: str | Path,
    *,
    thickness: float | None = None,
    count: int | None = None,
    max_frequency: float | None = None,
    damping: float = 0.01,
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    base_dir: str | Path = ".",
    key: str = "table.flexible",
) -> FlexibleTop:
    """A bending top from its modal file, as ``[table.flexible]`` gives it (:class:`FlexibleTop`).

    Parameters
    ----------
    modes : str or Path
        The modal file (CSV or UFF), relative to ``base_dir`` (the scenario file's folder; default the
        current one) or absolute.
    thickness : float, optional
        The top's thickness, ``[table] size`` z [m] (needed for a single layer of nodes).
    count, max_frequency, damping, origin
        As the keys of ``[table.flexible]``: the modes kept, the damping ratio where the file gives none, the
        file's origin in the table frame [m].
    base_dir : str or Path
        Where a relative ``modes`` lies.
    key : str
        The key named first in errors.

    Returns
    -------
    FlexibleTop

    Raises
    ------
    ScenarioError
        A bad key or modal file, naming it (the rigid modes are checked against the table by the scenario).
    """
    _check_arguments(count, max_frequency, damping)
    shift = tuple(number(v, f"origin[{i}]", error=ParameterError) for i, v in enumerate(origin))
    if len(shift) != 3:
        raise ParameterError(f"origin: must be three numbers [m], got {len(shift)}")
    try:
        data = load_modal_data(Path(base_dir) / modes, thickness=thickness, count=count,
                               max_frequency=max_frequency, damping=damping, origin=shift, key=f"{key}.modes")
    except ScenarioError as exc:
        text = str(exc)
        raise ScenarioError(text if text.startswith(key) else f"{key}.modes: {text}") from None
    return FlexibleTop(modes=str(modes), data=data, count=None if count is None else int(count),
                       max_frequency=max_frequency, damping=damping, origin=shift)


def _check_arguments(count: object, max_frequency: object, damping: object) -> None:
    """The numbers of :func:`load_flexible` (as :mod:`isolator.scenario.rules` has them for the file's keys)."""
    if count is not None and (isinstance(count, bool) or not isinstance(count, int | np.integer) or count < 1):
        raise ParameterError(f"count: must be a whole number >= 1, got {count!r}")
    if max_frequency is not None:
        number(max_frequency, "max_frequency", positive=True, error=ParameterError)
    number(damping, "damping", nonnegative=True, below=1.0, error=ParameterError)


def read_flexible(r: KeyReader, base_dir: Path, mass: float, size: Sequence[float] | None) -> FlexibleTop:
    """``[table.flexible]``: the modal file read and checked, its rigid modes against ``[table]`` ``mass`` [kg]
    and ``size`` [m]."""
    modes = r.string("modes")
    if not modes.strip():
        raise ScenarioError(f"{r.key('modes')}: must name a modal file (.csv, .unv or .uff)")
    count = r.number("count", positive=True) if r.has("count") else None
    if count is not None and count != int(count):
        raise ScenarioError(f"{r.key('count')}: must be a whole number, got {count:g}")
    max_frequency = r.number("max_frequency", positive=True) if r.has("max_frequency") else None
    damping = r.number("damping", 0.01, nonnegative=True, below=1.0)
    origin = r.vector("origin", (0.0, 0.0, 0.0))
    r.used.update(("count", "max_frequency"))
    r.finish()
    top = load_flexible(modes, thickness=None if size is None else size[2],
                        count=None if count is None else int(count),
                        max_frequency=max_frequency, damping=damping, origin=origin, base_dir=base_dir, key=r.path)
    check_top(top, mass, size, r.path)
    return top


def check_top(top: FlexibleTop, mass: float, size: Sequence[float] | None, key: str = "table.flexible") -> None:
    """The modal file's rigid modes against the table: mass within 1 % of ``mass`` [kg], mass centre within 1 % of
    the top's largest size (``size``, else the nodes' extent) [m] from the table frame's origin."""
    rigid = top.data.rigid
    if rigid is None:
        return
    largest = float(max(size)) if size is not None else float(np.ptp(top.data.nodes, axis=0).max())
    check_rigid(rigid, mass, largest, f"{key}.modes: '{top.data.path}'", top.origin)


def read_feet(r: KeyReader) -> Feet | None:
    """The ``feet`` key of a point or carriage: a non-empty list of ``[x, y]`` offsets [m]; None when absent."""
    r.used.add("feet")
    if not r.has("feet"):
        return None
    return as_feet(r.raw("feet"), r.key("feet"))


def as_feet(value: Any, key: str) -> Feet:
    """``value`` as feet: a non-empty list of ``(x, y)`` pairs of finite numbers [m]; else a ScenarioError."""
    if isinstance(value, str | bytes) or not isinstance(value, Sequence | np.ndarray) or len(value) == 0:
        raise ScenarioError(f"{key}: must be a non-empty list of [x, y] offsets (m)")
    out = []
    for i, foot in enumerate(value):
        if isinstance(foot, str | bytes) or not isinstance(foot, Sequence | np.ndarray) or len(foot) != 2:
            raise ScenarioError(f"{key}[{i}]: must be [x, y], two numbers (m)")
        x, y = (v.item() if isinstance(v, np.generic) else v for v in foot)
        out.append((number(x, f"{key}[{i}][0]"), number(y, f"{key}[{i}][1]")))
    return tuple(out)


def tupled_feet(value: Any) -> Any:
    """``feet`` given as lists (or an array) as tuples, so that the dataclass holding them hashes; anything else
    as it is (the checks refuse it, naming the key)."""
    if isinstance(value, Sequence | np.ndarray) and not isinstance(value, str | bytes) and all(
            isinstance(f, Sequence | np.ndarray) and not isinstance(f, str | bytes) for f in value):
        return tuple(tuple(f.tolist() if isinstance(f, np.ndarray) else f) for f in value)
    return value


def flexible_values(flexible: FlexibleTop | None, points: Sequence[Any], carriages: Sequence[Any]
                    ) -> Iterator[tuple[str, object]]:
    """The numbers of ``[table.flexible]`` and of the points' and carriages' ``feet``, by their file keys."""
    if flexible is not None:
        for name in ("count", "max_frequency"):
            if getattr(flexible, name) is not None:
                yield f"table.flexible.{name}", getattr(flexible, name)
        yield "table.flexible.damping", flexible.damping
        for i, v in enumerate(flexible.origin):
            yield f"table.flexible.origin[{i}]", v
    for section, things in (("points", points), ("carriages", carriages)):
        for k, thing in enumerate(things):
            for i, foot in enumerate(thing.feet or ()):
                for j, v in enumerate(foot if isinstance(foot, Sequence | np.ndarray) else (foot,)):
                    yield f"{section}[{k}].feet[{i}][{j}]", v
