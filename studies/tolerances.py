"""Manufacturing tolerances for the robustness study: parsing ``NAME=+-5%``, expanding them into the
parameters that vary independently, and drawing Latin-hypercube samples within them.

A tolerance names a model parameter as :attr:`isolator.ParameterLayout.names` gives it, or a group of them:
``[*]`` means every element (``isolators[*].stiffness``), and a name may stop at a vector
(``isolators[0].stiffness``: x, y and z). Each element varies on its own (every isolator is built
differently): ``isolators[*].stiffness=+-10%`` becomes one factor per isolator, applied to its three
components together (a relative tolerance keeps an isolator's axes in proportion), while an absolute
tolerance such as ``isolators[*].position=+-0.002`` (metres) varies every component on its own. The
values are uniform within the tolerance, drawn by Latin-hypercube sampling (:class:`scipy.stats.qmc.LatinHypercube`,
seeded: the same seed, the same machines).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

from isolator import ParameterError, ParameterLayout
from isolator.scenario.arguments import check_public
from isolator.sweep import resolve

__all__ = ["DEFAULT_TOLERANCES", "Tolerance", "Varied", "draw_samples", "parse_tolerance", "sweep_columns",
           "varied_parameters"]

#: what a built machine differs from its drawing by, when no ``--tolerance`` is given (names a scenario
#: does not have are left out: a pneumatic table has no ``stiffness`` entries)
DEFAULT_TOLERANCES = (
    "table.mass=+-5%",
    "carriages[*].mass=+-5%",
    "isolators[*].stiffness=+-10%",
    "isolators[*].damping=+-20%",
    "isolators[*].position=+-0.002",
)

_AMOUNT = re.compile(r"^\s*(?:\+-|±|\+/-)\s*([^%\s]+)\s*(%?)\s*$")


@dataclass(frozen=True)
class Tolerance:
    """A tolerance as given.

    Attributes
    ----------
    name : str
        A parameter name, with ``[*]`` or stopping at a vector allowed.
    amount : float
        The half-width: a fraction of the value (``relative``) or in the parameter's own unit (m, kg,
        N/m, N s/m).
    relative : bool
    """

    name: str
    amount: float
    relative: bool

    @property
    def label(self) -> str:
        """As it would be written: ``isolators[*].stiffness=+-10%``."""
        return f"{self.name}=+-{self.amount * 100:g}%" if self.relative else f"{self.name}=+-{self.amount:g}"


def parse_tolerance(text: str) -> Tolerance:
    """``NAME=+-5%`` (relative) or ``NAME=+-0.002`` (absolute, in the parameter's unit); ``±`` works too.

    Raises
    ------
    ParameterError
        Naming the text and what is wrong (no ``=``, no ``+-``, not a finite number > 0, 100 % or more).
    """
    name, sep, amount = text.partition("=")
    if not sep or not name.strip():
        raise ParameterError(f"--tolerance {text!r}: expected NAME=+-AMOUNT, e.g. isolators[*].stiffness=+-10%")
    match = _AMOUNT.match(amount)
    if match is None:
        raise ParameterError(f"--tolerance {text!r}: the amount must read +-5% (relative) or +-0.002 (absolute)")
    try:
        value = float(match[1])
    except ValueError:
        raise ParameterError(f"--tolerance {text!r}: {match[1]!r} is not a number") from None
    relative = match[2] == "%"
    value = value / 100.0 if relative else value
    if not math.isfinite(value) or value <= 0:
        raise ParameterError(f"--tolerance {text!r}: the amount must be a finite number > 0")
    if relative and value >= 1.0:
        raise ParameterError(f"--tolerance {text!r}: a relative tolerance must be below 100 %")
    return Tolerance(name.strip(), value, relative)


@dataclass(frozen=True)
class Varied:
    """One independently varied parameter (or vector, scaled as a whole).

    Attributes
    ----------
    name : str
        A layout name, or an element's vector name (``isolators[2].stiffness``).
    tolerance : Tolerance
        The tolerance it comes from.
    nominal : float
        The scenario's value (for a vector scaled as a whole: its first component's) [its unit].
    """

    name: str
    tolerance: Tolerance
    nominal: float

    @property
    def relative(self) -> bool:
        return self.tolerance.relative


def varied_parameters(
    tolerances: Sequence[Tolerance], layout: ParameterLayout, nominal: np.ndarray, *, skip_missing: bool = False
) -> list[Varied]:
    """The parameters the tolerances vary, each element (and, for absolute tolerances, each component) on
    its own, in the order given.

    Parameters
    ----------
    tolerances : sequence of Tolerance
    layout : ParameterLayout
        The scenario's (``Simulator(scenario).layout``).
    nominal : ndarray
        The scenario's parameter vector (``layout.pack(scenario)``).
    skip_missing : bool
        Leave out tolerances on names the scenario does not have (the defaults) instead of refusing them.

    Raises
    ------
    ParameterError
        An unknown name (with the closest known one), a name listed twice, or a tolerance on a parameter
        that cannot vary: a relative tolerance on a value of zero, or one whose range leaves the
        parameter's allowed values (a mass or stiffness at or below zero).
    """
    index = {name: i for i, name in enumerate(layout.names)}
    varied: list[Varied] = []
    for tol in tolerances:
        try:
            groups = _elements(tol, layout)
        except ParameterError:
            if skip_missing:
                continue
            raise
        for group, entries in groups.items():
            parts = [(group, entries)] if tol.relative else [(e, (e,)) for e in entries]
            for name, members in parts:
                values = np.array([nominal[index[e]] for e in members])
                if tol.relative and np.all(values == 0.0):
                    raise ParameterError(
                        f"--tolerance {tol.label}: {name} cannot vary by a fraction of its value, which is 0; "
                        f"give an absolute tolerance ({tol.name}=+-AMOUNT)")
                for sign in (-1.0, 1.0):
                    changed = {e: v * (1 + sign * tol.amount) if tol.relative else v + sign * tol.amount
                               for e, v in zip(members, values, strict=True)}
                    try:
                        layout.with_changes(nominal, changed)
                    except ParameterError as exc:
                        raise ParameterError(f"--tolerance {tol.label}: {name} cannot vary that much ({exc})") from None
                varied.append(Varied(name, tol, float(values[0])))
    names = [v.name for v in varied]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise ParameterError(f"--tolerance: {name} is varied by two tolerances; give it once")
    return varied


def _elements(tol: Tolerance, layout: ParameterLayout) -> dict[str, tuple[str, ...]]:
    """The layout names a tolerance's name matches (:func:`isolator.sweep.resolve`), grouped by element:
    ``isolators[*].stiffness`` -> ``{"isolators[0].stiffness": (".x", ".y", ".z" entries), ...}``."""
    try:
        column = resolve(layout, tol.name, "scale" if tol.relative else "set")
    except ParameterError as exc:
        raise ParameterError(f"--tolerance {tol.label}: {str(exc).split(': ', 1)[-1]}") from None
    depth = tol.name.count(".") + 1
    groups: dict[str, list[str]] = {}
    for i in column.entries:
        entry = layout.names[i]
        groups.setdefault(".".join(entry.split(".")[:depth]), []).append(entry)
    return {group: tuple(entries) for group, entries in groups.items()}


def draw_samples(varied: Sequence[Varied], count: int, seed: int = 0) -> np.ndarray:
    """``count`` machines (count, len(varied)): uniform within each tolerance by Latin-hypercube sampling.

    Each column is what a sweep takes for its parameter: the factor (relative tolerances, ``scale``) or the
    value itself in the parameter's unit (absolute tolerances, ``set``).
    """
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise ParameterError(f"samples: must be a whole number >= 1, got {count!r}")
    if not varied:
        raise ParameterError("tolerances: none of them names a parameter of this scenario")
    unit = qmc.LatinHypercube(d=len(varied), seed=seed).random(count)  # [0, 1)
    u = 2.0 * unit - 1.0
    amounts = np.array([v.tolerance.amount for v in varied])
    base = np.array([1.0 if v.relative else v.nominal for v in varied])
    return base + u * amounts


def sweep_columns(varied: Sequence[Varied], values: np.ndarray) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The samples as a zipped sweep's ``set`` (absolute) and ``scale`` (relative) columns, by name."""
    absolute: dict[str, np.ndarray] = {}
    relative: dict[str, np.ndarray] = {}
    for j, v in enumerate(varied):
        (relative if v.relative else absolute)[v.name] = values[:, j]
    return absolute, relative


check_public(globals())
