"""Swept names: a parameter name of ``Simulator(...).layout.names``, ``[*]`` for every element of a
collection (``isolators[*].stiffness.z``), or a name that stops at a vector or table
(``isolators[0].stiffness``: its three components; ``isolators[*].damping``: every component of every
isolator). One swept column drives every entry its name matches; ``Simulator.run(changes=...)`` takes the
same names (:func:`expand_changes`)."""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

from isolator.errors import ParameterError
from isolator.model.parameters import ParameterLayout
from isolator.scenario.rules import closest, rule_for

__all__ = ["Column", "expand_changes", "joint_entries", "resolve"]

_STAR = re.escape("[*]")
_INDEX = re.compile(r"\[\d+\]")


@dataclass(frozen=True)
class Column:
    """One swept name and the parameter entries it drives.

    Attributes
    ----------
    name : str
        As given (the output's column name).
    entries : tuple of int
        Indices into the parameter vector, in ``layout.names`` order.
    mode : {"set", "scale"}
        Its values are the entries' values [SI units], or factors [-] on the scenario's.
    """

    name: str
    entries: tuple[int, ...]
    mode: Literal["set", "scale"]


def resolve(layout: ParameterLayout, name: object, mode: Literal["set", "scale"], key: str | None = None) -> Column:
    """The entries ``name`` matches (``key``: how errors name it, default ``mode['name']``).

    Parameters
    ----------
    layout : ParameterLayout
        The scenario's structure (its :attr:`~ParameterLayout.names`).
    name : str
        A parameter's name, ``[*]`` for every element (``isolators[*].stiffness.z``) and a vector's name for
        all its components.
    mode : {"set", "scale"}
        Values given are the entries' values [SI units] or factors on the scenario's [-].
    key : str, optional
        How errors name the swept name; default ``mode['name']``.

    Returns
    -------
    Column
        The name and the parameter entries it drives, in ``layout.names`` order.

    Raises
    ------
    ParameterError
        ``set['isolators[*].stifness.z']: not a parameter of this scenario; did you mean ...``, or
        ``[*]`` after a name without elements.
    """
    key = f"{mode}[{name!r}]" if key is None else key
    if not isinstance(name, str) or not name:
        raise ParameterError(f"{key}: must be a parameter name (Simulator.layout.names lists them)")
    pattern = re.compile(re.escape(name).replace(_STAR, r"\[\d+\]") + r"(\..+)?")
    entries = tuple(i for i, n in enumerate(layout.names) if pattern.fullmatch(n))
    if entries:
        return Column(name, entries, mode)
    star = name.find("[*]")
    if star >= 0:
        head = name[:star]
        if not any(n.startswith(f"{head}[") for n in layout.names):
            collections = sorted({n.split("[")[0] for n in layout.names if "[" in n})
            raise ParameterError(f"{key}: '[*]' after '{head}', which has no elements (collections of this "
                                 f"scenario: {', '.join(collections)})")
    near = closest(name, _spellings(layout))
    hint = f"; did you mean '{near}'?" if near else ""
    raise ParameterError(f"{key}: not a parameter of this scenario{hint} (Simulator.layout.names lists them; "
                         "[*] for every element, a vector's name for all its components)")


def expand_changes(layout: ParameterLayout, changes: object, argument: str = "changes") -> object:
    """``changes`` by parameter name, with every name a sweep takes (``[*]``, a vector's or table's name) spread
    over the entries it matches; anything not a mapping is given back for
    :meth:`~isolator.model.parameters.ParameterLayout.with_changes` to refuse.

    Raises
    ------
    ParameterError
        ``changes['isolators[*].stifness.z']: not a parameter of this scenario; did you mean ...``.
    """
    if not isinstance(changes, Mapping):
        return changes
    known = set(layout.names)
    out: dict[object, object] = {}
    for name, value in changes.items():
        if isinstance(name, str) and name in known:
            out[name] = value
            continue
        column = resolve(layout, name, "set", f"{argument}[{name!r}]")
        out.update({layout.names[i]: value for i in column.entries})
    return out


def _spellings(layout: ParameterLayout) -> list[str]:
    """Every name a sweep accepts: the names, with ``[*]``, and their vectors and tables."""
    out: dict[str, None] = {}
    for name in layout.names:
        for form in (name, _INDEX.sub("[*]", name)):
            parts = form.split(".")
            for k in range(len(parts), 0, -1):
                out[".".join(parts[:k])] = None
    return list(out)


def joint_entries(layout: ParameterLayout) -> frozenset[int]:
    """Entries checked together with others (:meth:`ParameterLayout.check`): directions, principal inertia,
    isolator positions, damping-chamber volumes; a design that sweeps them is checked whole."""
    def joint(name: str) -> bool:
        rule = rule_for(name)
        directions = rule is not None and (rule.unit or rule.triangle)
        return directions or (name.startswith("isolators") and ".position." in name) or name.endswith(".damping_volume")
    return frozenset(i for i, n in enumerate(layout.names) if joint(n))
