"""One rule for every name a scenario defines, and control characters escaped wherever an input is printed.

Names travel further than the scenario file: into C string literals of an exported controller, CSV
headers, column names of a sweep, messages on a terminal. So each name a scenario defines (the scenario's
own, sensors, carriages, actuators, isolators, points, leveling groups, disturbances) follows one rule,
:func:`check_name`: a string of at most :data:`MAX_NAME` printable characters (no control characters, no
NUL, no line breaks, no invisible formatting characters such as bidirectional overrides), without leading
or trailing spaces, and not beginning with ``=``, ``+``, ``-`` or ``@`` (:data:`FORMULA_STARTS`: a
spreadsheet opening a CSV whose header holds such a name runs it as a formula). :func:`check_names` adds
that each name is used once in its section.

Text that is printed from an input and cannot be refused (a message quoting a file's header, a path)
goes through :func:`escaped` first: every character that is not printable is written as its Python
escape, so that no input moves the terminal's cursor, changes its colours or splits a one-line message.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from isolator.errors import ScenarioError

__all__ = ["EXCERPT", "FORMULA_STARTS", "MAX_NAME", "check_name", "check_names", "check_scenario_names", "escaped",
           "excerpt"]

#: the longest name [characters]
MAX_NAME = 100
#: the most of a file's text (a header, a cell) a message quotes [characters]
EXCERPT = 24
#: the characters no name begins with: a spreadsheet reads a CSV cell beginning with one as a formula
#: (``=HYPERLINK(...)`` in a column's header becomes a live link)
FORMULA_STARTS = "=+-@"


def escaped(text: object, limit: int | None = None) -> str:
    """``text`` with every non-printable character escaped (``\\x1b``, ``\\n``, ``\\u202e``), at most
    ``limit`` characters of it (then ``...``).

    Examples
    --------
    >>> escaped("\\x1b[31mred\\x1b[0m")
    '\\\\x1b[31mred\\\\x1b[0m'
    >>> escaped("a" * 50, limit=8)
    'aaaaaaaa...'
    """
    text = str(text)
    cut = limit is not None and len(text) > limit
    if cut:
        text = text[:limit]
    out = text if text.isprintable() else "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
    return out + "..." if cut else out


def excerpt(text: object) -> str:
    """What a message quotes of a file's text (a header, a cell): at most :data:`EXCERPT` characters,
    escaped (:func:`escaped`)."""
    return escaped(text, EXCERPT)


def check_name(name: object, key: str, *, optional: bool = False, longest: int | None = MAX_NAME) -> str:
    """``name`` if it follows the rule for names; else a :class:`ScenarioError` naming ``key``.

    Parameters
    ----------
    name : object
        The name to check.
    key : str
        The scenario key it came from (``carriages[0].name``).
    optional : bool
        Whether the empty string is allowed (a name the section does not need, such as an isolator's).
    longest : int or None
        The most characters (None: any length; the scenario's own name, which never enters code or a
        column, and whose default output names are cut to 100 characters).

    Returns
    -------
    str
        ``name``.

    Raises
    ------
    ScenarioError
        Not a string, empty (unless ``optional``), longer than ``longest``, with a character that is
        not printable, with leading or trailing spaces, or beginning with one of :data:`FORMULA_STARTS`;
        the name quoted escaped.

    Examples
    --------
    >>> check_name("x-stage", "carriages[0].name")
    'x-stage'
    >>> check_name("a\\x00b", "carriages[0].name")
    Traceback (most recent call last):
    ...
    isolator.errors.ScenarioError: carriages[0].name: must be at most 100 printable characters ...
    """
    if not isinstance(name, str):
        raise ScenarioError(f"{key}: must be a string, got {type(name).__name__}")
    if not name and optional:
        return name
    if not name.strip() or name != name.strip():
        raise ScenarioError(f"{key}: must be a non-empty name without leading or trailing spaces, "
                            f"got '{escaped(name, 40)}'")
    if (longest is not None and len(name) > longest) or not name.isprintable():
        most = "" if longest is None else f"at most {longest} "
        raise ScenarioError(f"{key}: must be {most}printable characters (no control characters, line breaks or "
                            f"invisible formatting), got '{escaped(name, 40)}'")
    if name[0] in FORMULA_STARTS:
        raise ScenarioError(f"{key}: must not begin with '{name[0]}' (a spreadsheet opening a CSV with this name "
                            f"in its header would run it as a formula), got '{escaped(name, 40)}'")
    return name


def check_names(names: Iterable[object], section: str, *, optional: bool = False) -> None:
    """Each name of a section by :func:`check_name` (keys ``section[i].name``), and each used once.

    Raises
    ------
    ScenarioError
        The first name that breaks the rule, or the second use of a name, named by its key.
    """
    seen: set[object] = set()
    for i, name in enumerate(names):
        check_name(name, f"{section}[{i}].name", optional=optional)
        if name in seen and name != "":
            raise ScenarioError(f"{section}[{i}].name: '{name}' is used twice")
        seen.add(name)


def check_scenario_names(scenario: Any) -> None:
    """Every name a :class:`~isolator.scenario.definitions.Scenario` defines, by :func:`check_names`: its own
    (key ``name``, of any length), and those of its isolators (optional), carriages, actuators, points,
    sensors, leveling groups and disturbances (where the scenario has them).

    Raises
    ------
    ScenarioError
        The first name that breaks the rule or is used twice in its section, named by its key.
    """
    check_name(scenario.name, "name", longest=None)
    check_names([iso.name for iso in scenario.isolators], "isolators", optional=True)
    for section in ("carriages", "actuators", "points", "sensors", "leveling", "disturbances"):
        check_names([item.name for item in getattr(scenario, section, ())], section)
