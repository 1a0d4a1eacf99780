"""The isolators' uncertainty a robustness check covers: relative bounds and named intervals.

An :class:`Uncertainty` holds relative bounds on every isolator's stiffness and damping together (the
scale factors ``1 +- bound`` of :meth:`isolator.Simulator.scaled_parameters`) and intervals of named
parameters (absolute values, such as a calibration's 95 % intervals, :func:`uncertainty_from_calibration`).
Each bound or interval is one dimension of a box; :meth:`Uncertainty.samples` picks the points of the box
to check (the scheme is in its description).
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

import numpy as np
from scipy.stats import qmc

from isolator.errors import ParameterError
from isolator.model.names import expand_changes
from isolator.model.parameters import ParameterLayout
from isolator.scenario.arguments import check_public
from isolator.scenario.files import parse_json, read_input_text
from isolator.scenario.names import escaped
from isolator.scenario.rules import closest
from isolator.simulation.scaling import scaled_parameter_sets

__all__ = ["Uncertainty", "parse_uncertainty", "uncertainty_from_calibration"]

#: the keys of :func:`parse_uncertainty`
SCALED = ("stiffness", "damping")
#: the box's corners are checked up to this many dimensions (then the scheme of :meth:`Uncertainty.samples`)
CORNERS = 4
#: scrambled Sobol points in the box beyond :data:`CORNERS` dimensions
SOBOL_POINTS = 16

_PERCENT = re.compile(r"^(?:\+-|\+/-|±)?\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*%$")


@dataclass(frozen=True)
class Uncertainty:
    """Relative bounds on the isolators' stiffness and damping, and intervals of named parameters.

    Attributes
    ----------
    stiffness : float
        Relative bound [-]: every isolator's stiffness scaled by ``1 - stiffness .. 1 + stiffness`` together
        (``0 <= stiffness < 1``; 0.2 is +-20 %).
    damping : float
        The same for the damping (``0 <= damping <= 1``; 1 lets it vanish, spring-dampers only).
    intervals : mapping of str to (float, float)
        ``name -> (low, high)``: absolute values [SI] of named parameters (as :meth:`isolator.Simulator.
        parameter_vector` names them, e.g. ``isolators[*].stiffness.z``), set after the scaling.

    Notes
    -----
    The nominal point is the scenario as it is (scales 1, the named parameters at the scenario's values).
    """

    stiffness: float = 0.0
    damping: float = 0.0
    intervals: Mapping[str, tuple[float, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for key, top in (("stiffness", 1.0), ("damping", 1.0 + 1e-12)):
            value = getattr(self, key)
            if not (math.isfinite(value) and 0.0 <= value < top):
                limit = "< 1" if key == "stiffness" else "<= 1"
                raise ParameterError(f"{key}: must be a relative bound >= 0 and {limit} (0.2 is +-20 %), got {value!r}")
            object.__setattr__(self, key, float(value))
        checked: dict[str, tuple[float, float]] = {}
        for name, bounds in dict(self.intervals).items():
            try:
                low, high = (float(v) for v in bounds)
            except (TypeError, ValueError):
                raise ParameterError(f"intervals[{name!r}]: must be (low, high), got {bounds!r}") from None
            if name in SCALED:
                raise ParameterError(f"intervals[{name!r}]: is the relative bound {name}=, not a parameter's name")
            if not (isinstance(name, str) and math.isfinite(low) and math.isfinite(high) and low <= high):
                raise ParameterError(f"intervals[{name!r}]: must be finite with low <= high, got {bounds!r}")
            checked[name] = (low, high)
        object.__setattr__(self, "intervals", MappingProxyType(checked))

    @property
    def dimensions(self) -> tuple[tuple[str, float, float], ...]:
        """``(name, low, high)`` of each uncertain dimension: ``stiffness`` and ``damping`` as scale factors
        [-], then the intervals [SI]; a zero bound is no dimension."""
        out = [(key, 1.0 - b, 1.0 + b) for key in SCALED if (b := getattr(self, key)) > 0.0]
        return tuple(out) + tuple((n, lo, hi) for n, (lo, hi) in self.intervals.items())

    def samples(self) -> list[tuple[tuple[str, float], ...]]:
        """The points of the box to check, each the changed dimensions as ``(name, value)`` (``()``: nominal).

        Up to 2 dimensions: every combination of low, nominal and high (9 points for stiffness and
        damping); 3 or 4: the nominal and the ``2^d`` corners; more: the nominal, each dimension alone at
        its low and its high end, all low, all high, and :data:`SOBOL_POINTS` scrambled Sobol points in
        the box (seed 0, reproducible).
        """
        dims = self.dimensions
        names = [d[0] for d in dims]
        if not dims:
            return [()]
        if len(dims) <= 2:
            levels = [(None, lo, hi) for _, lo, hi in dims]
            return [tuple((n, v) for n, v in zip(names, row, strict=True) if v is not None)
                    for row in itertools.product(*levels)]
        lows, highs = np.array([d[1] for d in dims]), np.array([d[2] for d in dims])
        out: list[tuple[tuple[str, float], ...]] = [()]
        if len(dims) <= CORNERS:
            points = lows + np.array(list(itertools.product((0, 1), repeat=len(dims)))) * (highs - lows)
        else:
            for name, lo, hi in dims:
                out += [((name, lo),), ((name, hi),)]
            sobol = qmc.Sobol(len(dims), scramble=True, seed=0).random(SOBOL_POINTS)
            points = np.vstack([lows, highs, lows + sobol * (highs - lows)])
        return out + [tuple((n, float(v)) for n, v in zip(names, row, strict=True)) for row in points]

    def parameters(self, layout: ParameterLayout, nominal: np.ndarray, sample: Sequence[tuple[str, float]]
                   ) -> np.ndarray:
        """The model's parameter vector at one of :meth:`samples` (``nominal``: the scenario's own).

        Raises
        ------
        ParameterError
            A named parameter the scenario does not have (with the closest), or a scale it refuses.
        """
        values = dict(sample)
        scales = {key: values.pop(key, 1.0) for key in SCALED}
        p = nominal
        if scales["stiffness"] != 1.0 or scales["damping"] != 1.0:
            p = scaled_parameter_sets(layout, nominal, scales["stiffness"], scales["damping"])[0]
        if values:
            p = layout.with_changes(p, expand_changes(layout, values, "uncertainty"))  # type: ignore[arg-type]
        return p

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: ``stiffness``, ``damping`` (relative bounds) and ``intervals`` (``name: [low, high]``)."""
        return {"stiffness": self.stiffness, "damping": self.damping,
                "intervals": {n: list(v) for n, v in self.intervals.items()}}


def parse_uncertainty(text: str) -> Uncertainty:
    """The command line's ``--uncertainty``: ``stiffness=+-20%,damping=+-30%``.

    Each item is ``KEY=+-P%`` with ``KEY`` ``stiffness`` or ``damping`` (every isolator's, together); the
    ``+-`` (or ``+/-``, ``±``) may be left out (``stiffness=20%`` is the same symmetric bound), the percent
    sign may not (a bare ``20`` could be a factor). ``P`` below 100 for the stiffness, up to 100 for the
    damping. Named parameters' intervals come from a calibration (:func:`uncertainty_from_calibration`)
    or :class:`Uncertainty` directly.

    Parameters
    ----------
    text : str
        The option's value.

    Returns
    -------
    Uncertainty
        The relative bounds on every isolator's stiffness and damping.

    Raises
    ------
    ParameterError
        One line naming ``--uncertainty``, the item and what is wrong.

    Examples
    --------
    >>> from controllers.feedback import parse_uncertainty
    >>> uncertainty = parse_uncertainty("stiffness=+-20%,damping=+-30%")
    >>> uncertainty.stiffness, uncertainty.damping
    (0.2, 0.3)
    """
    bounds: dict[str, float] = {}
    items = [item.strip() for item in text.split(",")]
    if not text.strip():
        raise ParameterError("--uncertainty: empty; write e.g. stiffness=+-20%,damping=+-30%")
    for item in items:
        key, sep, value = (part.strip() for part in item.partition("="))
        if not sep or not key:
            raise ParameterError(f"--uncertainty: {item!r} is not KEY=+-P% (e.g. stiffness=+-20%,damping=+-30%)")
        if key not in SCALED:
            near = closest(key, list(SCALED))
            hint = f"; did you mean '{near}'?" if near else ""
            raise ParameterError(f"--uncertainty: unknown key {key!r}{hint} (keys: {', '.join(SCALED)})")
        if key in bounds:
            raise ParameterError(f"--uncertainty: {key} given twice")
        match = _PERCENT.match(value)
        if match is None:
            raise ParameterError(f"--uncertainty: {key}={value!r} must be a percentage such as +-20% "
                                 "(the percent sign is needed)")
        percent = float(match.group(1))
        if not (percent < 100.0 or (key == "damping" and percent == 100.0)):
            limit = "at most 100 %" if key == "damping" else "below 100 % (the isolators would hold nothing)"
            raise ParameterError(f"--uncertainty: {key}=+-{percent:g}% must be {limit}")
        bounds[key] = percent / 100.0
    return Uncertainty(stiffness=bounds.get("stiffness", 0.0), damping=bounds.get("damping", 0.0))


def uncertainty_from_calibration(path: str | Path, unidentified: bool = False) -> Uncertainty:
    """The 95 % intervals of a calibration's parameters (the JSON of ``isolator calibrate --json``).

    Parameters
    ----------
    path : str or Path
        The JSON file: ``{"parameters": {name: {"value", "std", "ci95": [low, high]}, ...}, ...}``.
    unidentified : bool
        Include the parameters the records do not fix (``std`` null; their ``ci95`` is then the fit's
        bounds, usually far wider than the truth). Default: left out.

    Returns
    -------
    Uncertainty
        The named parameters' intervals (``intervals``), as the robustness check takes them.

    Raises
    ------
    ParameterError
        One line naming the file: unreadable, not JSON, without valid ``parameters``, or (without
        ``unidentified``) none with a finite ``std``.
    """
    text = read_input_text(path, "calibration JSON", error=ParameterError, bom=False)
    data = parse_json(text, escaped(path, 120))
    parameters = data.get("parameters") if isinstance(data, dict) else None
    if not isinstance(parameters, dict) or not parameters:
        raise ParameterError(f"{path}: no 'parameters' in the calibration JSON (as isolator calibrate --json "
                             "writes it)")
    intervals: dict[str, tuple[float, float]] = {}
    for name, entry in parameters.items():
        ci = entry.get("ci95") if isinstance(entry, dict) else None
        ok = isinstance(ci, list) and len(ci) == 2 and all(isinstance(v, int | float) and not isinstance(v, bool)
                                                           and math.isfinite(v) for v in ci)
        if not ok or ci[0] > ci[1]:  # type: ignore[index]
            raise ParameterError(f"{path}: parameters.{name}.ci95 must be [low, high] finite numbers, got "
                                 f"{ci!r}")
        if entry.get("std") is None and not unidentified:
            continue
        intervals[str(name)] = (float(ci[0]), float(ci[1]))  # type: ignore[index]
    if not intervals:
        raise ParameterError(f"{path}: no parameter the records fix (every std is null; unidentified=True takes "
                             "their bounds as intervals)")
    return Uncertainty(intervals=intervals)


check_public(globals())
