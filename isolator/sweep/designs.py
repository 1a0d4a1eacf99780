"""The designs of a sweep: swept columns and their values, crossed (a grid), zipped, or sampled
(Sobol or Latin hypercube over ranges, :mod:`scipy.stats.qmc`)."""

from __future__ import annotations

import itertools
import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from isolator.errors import ParameterError
from isolator.model.parameters import ParameterLayout
from isolator.scenario.files import check_memory
from isolator.scenario.rules import check_value
from isolator.sweep.names import Column, resolve

__all__ = ["DESIGN_BYTES", "METHODS", "Designs", "Values", "build_designs", "check_design_count"]

#: sampling methods of ``samples=``
METHODS = ("sobol", "lhs")
#: memory [bytes] a design takes besides its swept values (16 bytes each): the grid's tuple while it is built,
#: its row of values and parameters, its row of the result's columns
DESIGN_BYTES = 512.0

#: a swept name's values: a list (grid, zip), or a range ``(low, high)`` with ``samples``
Values = Sequence[float] | np.ndarray


@dataclass(frozen=True)
class Designs:
    """Swept columns and one row of their values per design, in design order.

    Attributes
    ----------
    columns : tuple of Column
    values : ndarray (designs, columns)
        Absolute values [SI units] for ``set`` columns, factors [-] for ``scale`` columns.
    base : ndarray (parameters,)
        The scenario's parameter vector.
    """

    columns: tuple[Column, ...]
    values: np.ndarray
    base: np.ndarray

    @property
    def count(self) -> int:
        """Designs."""
        return int(self.values.shape[0])

    @property
    def names(self) -> tuple[str, ...]:
        """The swept names as given."""
        return tuple(c.name for c in self.columns)

    @property
    def scaled(self) -> tuple[str, ...]:
        """The swept names whose values are factors on the scenario's."""
        return tuple(c.name for c in self.columns if c.mode == "scale")

    def parameters(self, start: int, stop: int) -> np.ndarray:
        """Parameter vectors (stop - start, parameters) of designs ``start`` to ``stop - 1``."""
        values = self.values[start:stop]
        out = np.repeat(self.base[None, :], values.shape[0], axis=0)
        for j, column in enumerate(self.columns):
            at = list(column.entries)
            v = values[:, j : j + 1]
            out[:, at] = v if column.mode == "set" else self.base[at][None, :] * v
        return out


def build_designs(
    layout: ParameterLayout,
    base: np.ndarray,
    set: Mapping[str, Values] | None = None,
    scale: Mapping[str, Values] | None = None,
    zip: bool = False,
    samples: int | None = None,
    method: Literal["sobol", "lhs"] = "sobol",
    seed: int = 0,
) -> Designs:
    """The designs of :func:`isolator.sweep.sweep`'s arguments (there documented), checked.

    Parameters
    ----------
    layout : ParameterLayout
        The scenario's structure.
    base : ndarray
        The scenario's parameter vector, which ``scale`` multiplies and the unswept entries keep.
    set : mapping of str to values, optional
        Absolute values by name, as :func:`isolator.sweep.sweep` takes them.
    scale : mapping of str to values, optional
        Factors on the scenario's values by name.
    zip : bool
        Lists zipped (one design per position) instead of crossed.
    samples : int, optional
        Designs drawn over ``(low, high)`` ranges instead of a grid.
    method : {"sobol", "lhs"}
        How ``samples`` are drawn.
    seed : int
        Seed of the samples.

    Returns
    -------
    Designs
        The swept columns, their values per design and the base vector.

    Raises
    ------
    ParameterError
        Naming the argument: an unknown name, two names driving one entry, an empty or non-numeric list,
        zipped lists of different lengths, a range that is not ``(low, high)``, a value its parameter's
        rule refuses (:mod:`isolator.scenario.rules`), a bad ``samples`` or ``method``.
    """
    given: list[tuple[Literal["set", "scale"], str, object]] = []
    for mode, mapping in (("set", set), ("scale", scale)):
        if mapping is None:
            continue
        if not isinstance(mapping, Mapping):
            raise ParameterError(f"{mode}: must be a mapping of parameter names to values, got "
                                 f"{type(mapping).__name__}")
        given += [(mode, name, values) for name, values in mapping.items()]  # type: ignore[misc]
    if not given:
        raise ParameterError("set, scale: give at least one parameter to sweep (Simulator.layout.names)")
    columns = tuple(resolve(layout, name, mode) for mode, name, _ in given)
    owner: dict[int, str] = {}
    for c in columns:
        for i in c.entries:
            if i in owner:
                raise ParameterError(f"{c.mode}[{c.name!r}]: drives {layout.names[i]}, which "
                                     f"'{owner[i]}' drives already")
            owner[i] = c.name
    lists = [_numbers(values, f"{c.mode}[{c.name!r}]") for c, (_, _, values) in zip_(columns, given)]
    if samples is None:
        count = lists[0].size if zip else math.prod(v.size for v in lists)
        check_design_count(count, len(columns), ", ".join(f"{c.mode}[{c.name!r}]" for c in columns))
    if samples is not None:
        values = _sampled(columns, lists, samples, method, seed, zip)
    elif zip:
        lengths = {c.name: v.size for c, v in zip_(columns, lists)}
        if len(set_(lengths.values())) > 1:
            raise ParameterError("zip: the zipped lists must have one length, got "
                                 + ", ".join(f"{n}: {k}" for n, k in lengths.items()))
        values = np.column_stack(lists)
    else:
        values = np.array(list(itertools.product(*lists)), dtype=float).reshape(-1, len(columns))
    for c, v in zip_(columns, lists):  # the rules are intervals: the extremes stand for every value
        for value in {float(np.min(v)), float(np.max(v))}:
            for i in c.entries:
                check_value(layout.names[i], value if c.mode == "set" else base[i] * value,
                            f"{c.mode}[{c.name!r}] = {value:g}", ParameterError)
    return Designs(columns, values, np.asarray(base, dtype=float))


zip_, set_ = zip, set  # the builtins, under the arguments' names


def check_design_count(count: int, columns: int, what: str) -> None:
    """Refuse, before a byte of them is made, more designs than this machine's memory holds (:data:`DESIGN_BYTES`
    each and 16 per swept column): one :class:`ParameterError` starting with ``what`` (the key or option that
    asks for them), with the count.

    Examples
    --------
    >>> check_design_count(10**15, 1, "samples")
    Traceback (most recent call last):
    ...
    isolator.errors.ParameterError: samples: 1000000000000000 designs need about ... of memory, more than ...
    """
    check_memory(count * (DESIGN_BYTES + 16.0 * columns), f"{what}: {count} designs",
                 "sweep fewer designs (a coarser grid, fewer samples)")


def _numbers(values: object, key: str) -> np.ndarray:
    """A non-empty list of finite numbers."""
    if isinstance(values, str | bytes | bool):
        raise ParameterError(f"{key}: must be a list of numbers, got {values!r}")
    try:
        array = np.atleast_1d(np.asarray(values, dtype=float))
    except (TypeError, ValueError):
        raise ParameterError(f"{key}: must be a list of numbers, got {values!r}") from None
    if array.ndim != 1 or array.size == 0:
        raise ParameterError(f"{key}: must be a non-empty list of numbers, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ParameterError(f"{key}: must be finite numbers, got {array[~np.isfinite(array)][0]}")
    return array


def _sampled(columns: tuple[Column, ...], ranges: list[np.ndarray], samples: object, method: str, seed: int,
             zipped: bool) -> np.ndarray:
    """``samples`` designs over the ranges, Sobol (scrambled) or Latin hypercube, seeded."""
    from scipy.stats import qmc

    if zipped:
        raise ParameterError("zip: not with samples (sampled designs draw every name's value together)")
    if isinstance(samples, bool) or not isinstance(samples, int | np.integer) or samples < 1:
        raise ParameterError(f"samples: must be a whole number >= 1, got {samples!r}")
    check_design_count(int(samples), len(columns), "samples")
    if method not in METHODS:
        raise ParameterError(f"method: must be one of {', '.join(METHODS)}, got {method!r}")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ParameterError(f"seed: must be a whole number >= 0, got {seed!r}")
    for c, r in zip_(columns, ranges):
        if r.size != 2 or not r[0] < r[1]:
            raise ParameterError(f"{c.mode}[{c.name!r}]: with samples, a range (low, high) with low < high, "
                                 f"got {r.tolist()}")
    d = len(columns)
    engine = qmc.Sobol(d, scramble=True, seed=seed) if method == "sobol" else qmc.LatinHypercube(d, seed=seed)
    with warnings.catch_warnings():  # Sobol's balance wants a power of 2; any count is still a fine design
        warnings.simplefilter("ignore", UserWarning)
        unit = engine.random(int(samples))
    low, high = np.array([r[0] for r in ranges]), np.array([r[1] for r in ranges])
    return np.asarray(qmc.scale(unit, low, high), dtype=float)
