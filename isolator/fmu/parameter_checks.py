"""The plant FMU's tunable parameters checked by the scenario reader's rules when its initialisation ends.

The rules are :data:`isolator.scenario.rules.RULES`, the ones the file reader and ``changes=`` check by; the
FMU's C gets each tunable parameter's bounds and the rule in the words of
:meth:`~isolator.scenario.rules.Rule.problem`, and the vectors (a direction, principal moments of inertia) a
tunable parameter is part of, so that ``fmi2ExitInitializationMode`` refuses what the reader would, naming
the parameter and the reason (``docs/scenario-format.md``, "Additions to the budget and the FMU").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from isolator.model.parameters import ParameterLayout
from isolator.scenario.rules import FINITE, MAGNITUDE, UNIT_TOLERANCE, Rule, rule_for, vector_problem

__all__ = ["parameter_checks"]

#: what the C's vector checks are (``UNIT``, ``TRIANGLE`` in ``plant.c.j2``)
_UNIT, _TRIANGLE = 1, 2


def _words(problem: str | None) -> str:
    """A rule's problem without the value it was given (``must be >= 0, got -1`` -> ``must be >= 0``)."""
    if problem is None:
        raise ValueError("a probe value meant to break a rule did not")
    return problem.rpartition(", got ")[0] or problem


def _bound(name: str, rule: Rule) -> dict[str, Any]:
    """One tunable parameter's bounds (infinite where it has none) and its rule in words."""
    low = -math.inf if rule.low is None else rule.low
    high = math.inf if rule.high is None else rule.high
    if rule.low is not None:  # a value just below the low end (or at an open one) shows the rule's words
        words = _words(rule.problem(rule.low if rule.low_open else math.nextafter(rule.low, -math.inf)))
    elif rule.high is not None:
        words = _words(rule.problem(rule.high if rule.high_open else math.nextafter(rule.high, math.inf)))
    else:
        words = "must be finite"
    # a positive low end: a value <= 0 is told the sign first (as Rule.problem tells it)
    sign = _words(rule.problem(0.0)) if rule.low is not None and rule.low > 0 else words
    return {"name": name, "rule": words, "sign": sign, "low": max(low, -MAGNITUDE), "high": min(high, MAGNITUDE),
            "low_open": rule.low_open, "high_open": rule.high_open}


def parameter_checks(layout: ParameterLayout, tunable: Sequence[tuple[str, tuple[int, ...]]]
                     ) -> dict[str, Any]:
    """What ``plant.c.j2`` checks the tunable parameters by.

    Parameters
    ----------
    layout : ParameterLayout
        The parameters' names (``layout.names``) and so their rules.
    tunable : sequence of (str, tuple of int)
        Each tunable parameter's name and the entries of the parameter vector it sets.

    Returns
    -------
    dict
        ``bounds``: per tunable parameter, its name, the rule in words (``rule``; ``sign``: what a value <= 0
        is told), ``low``, ``high`` and whether they are open; ``vectors``: the unit vectors and principal
        moments the tunable entries are part of (name, rule in words, kind, the three entries);
        ``magnitude``, ``magnitude_rule``, ``unit_tolerance``.
    """
    names = layout.names
    bounds = [_bound(name, rule_for(names[entries[0]]) or FINITE) for name, entries in tunable]
    touched = {e for _, entries in tunable for e in entries}
    groups: dict[str, list[int]] = {}
    for i, name in enumerate(names):
        head, _, last = name.rpartition(".")
        rule = rule_for(name)
        if last in ("x", "y", "z") and rule is not None and (rule.unit or rule.triangle):
            groups.setdefault(head, []).append(i)
    vectors = []
    for head, members in groups.items():
        if len(members) != 3 or not touched & set(members):
            continue
        rule = rule_for(names[members[0]])
        kind = _UNIT if rule is not None and rule.unit else _TRIANGLE
        probe = [2.0, 0.0, 0.0] if kind == _UNIT else [1.0, 1.0, 3.0]
        vectors.append({"name": head, "rule": _words(vector_problem(head, probe)), "kind": kind,
                        "entries": members})
    return {"bounds": bounds, "vectors": vectors, "magnitude": MAGNITUDE,
            "magnitude_rule": _words(FINITE.problem(2 * MAGNITUDE)), "unit_tolerance": UNIT_TOLERANCE}
