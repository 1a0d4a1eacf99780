"""Robustness of an output-feedback controller over the carriages' travel and the isolators' uncertainty.

:func:`check_robustness` closes the loop of a :class:`DiscreteController` (sensors in, commands out, as
the simulation and the exported C run it) around the sampled sensor plant by
:func:`isolator.analysis.closed_loop.sampled_loop` (zero-order hold, the actuators' lag, one sample of
delay when the controller's ``delay`` says so, a bending top's elastic modes; the same loop ``isolator
check-controller`` and ``isolator simulate --controller`` check) in every combination of

* the carriages' positions: for each carriage the smallest, the largest and the middle of the positions
  its profile (or the ``[sequence]``) visits, and the start and end positions
  (:func:`isolator.model.tipping.travel_configurations`, duplicates removed), or positions given;
* the points of the uncertainty box (:meth:`~controllers.feedback.uncertainty.Uncertainty.samples`).

Each case gives the spectral radius and the margins at the plant's input
(:mod:`controllers.feedback.loop_margins`); the :class:`RobustnessReport` gives the worst cases. The
closed loop is taken without disturbances; the actuators' clipping at ``max_force`` is left out (small
motions about the rest configuration).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from isolator.analysis.closed_loop import SampledLoop, sampled_loop
from isolator.analysis.linear import linearise, rest_positions
from isolator.errors import ParameterError, UnstableClosedLoopError, UnstableTableError
from isolator.model.parameters import ParameterLayout
from isolator.model.tipping import travel_configurations
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.simulation.discrete_controller import DiscreteController

from .loop_margins import LoopMargins, sampled_margins
from .uncertainty import SCALED, Uncertainty

__all__ = ["RobustnessCase", "RobustnessReport", "check_robustness"]

#: the margins a report ranks, and whether the smallest (True) or the largest (False) is the worst
MARGINS = {"gain_margin": True, "gain_margin_low": False, "phase_margin": True, "loop_disk_margin": True,
           "disk_margin": True}


def _describe_values(values: Sequence[tuple[str, float]]) -> str:
    """``stiffness x0.8, damping x1.3, isolators[*].damping.z = 4560`` (``nominal parameters`` when empty)."""
    if not values:
        return "nominal parameters"
    return ", ".join(f"{n} x{v:.4g}" if n in SCALED else f"{n} = {v:.6g}" for n, v in values)


def _describe_positions(carriages: Sequence[str], q: Sequence[float] | np.ndarray) -> str:
    """``x-stage at 0.7 m, y-stage at -0.3 m`` (``no carriages`` without)."""
    return ", ".join(f"{n} at {v:.4g} m" for n, v in zip(carriages, q, strict=True)) or "no carriages"


@dataclass(frozen=True)
class RobustnessCase:
    """One rest configuration and parameter point of a robustness check.

    Attributes
    ----------
    carriages : tuple of str
        Names in file order.
    positions : tuple of float
        Each carriage's position along its axis [m].
    values : tuple of (str, float)
        The uncertain parameters changed from the scenario: ``stiffness``/``damping`` scale factors [-],
        named parameters [SI]; empty for the nominal.
    spectral_radius : float
        Of the sampled closed loop [-] (stable below 1).
    margins : LoopMargins or None
        At the plant's input; None when the loop is unstable (margins mean nothing there) or the margins
        were not asked for.
    growing : str
        An unstable case's growing oscillation: ``an oscillation at 441 Hz grows, from the open-loop mode
        'plate 1' (442.3 Hz)`` (:meth:`~isolator.analysis.closed_loop.SampledLoop.growing_mode`); empty when
        stable.
    """

    carriages: tuple[str, ...]
    positions: tuple[float, ...]
    values: tuple[tuple[str, float], ...]
    spectral_radius: float
    margins: LoopMargins | None
    growing: str = ""

    @property
    def stable(self) -> bool:
        """The spectral radius is below 1."""
        return self.spectral_radius < 1.0

    @property
    def where(self) -> str:
        """``x-stage at 0.7 m, y-stage at -0.3 m, stiffness x0.8, damping x1.3``."""
        return f"{_describe_positions(self.carriages, self.positions)}, {_describe_values(self.values)}"

    def margin(self, name: str) -> float:
        """One margin by name (:data:`MARGINS`): the actuators' smallest (or largest, ``gain_margin_low``);
        NaN when unstable."""
        if self.margins is None:
            return math.nan
        value = getattr(self.margins, name)
        return float(value) if np.ndim(value) == 0 else float(np.max(value) if not MARGINS[name] else np.min(value))

    def to_dict(self, actuators: Sequence[str] = ()) -> dict[str, Any]:
        """JSON-ready (infinite margins as null), per-actuator margins by name when ``actuators`` are given."""
        out: dict[str, Any] = {"positions": dict(zip(self.carriages, self.positions, strict=True)),
                               "parameters": dict(self.values), "spectral_radius": self.spectral_radius,
                               "stability_margin": 1.0 - self.spectral_radius, "stable": self.stable}
        for name in MARGINS:
            out[name] = _json(self.margin(name))
        if self.margins is not None:
            mg = self.margins
            out["disk_frequency_hz"] = mg.disk_frequency
            if actuators:
                out["actuators"] = {a: {"gain_margin": _json(mg.gain_margin[i]),
                                        "gain_margin_low": _json(mg.gain_margin_low[i]),
                                        "gain_frequency_hz": _json(mg.gain_frequency[i]),
                                        "phase_margin_deg": _json(mg.phase_margin[i]),
                                        "phase_frequency_hz": _json(mg.phase_frequency[i]),
                                        "loop_disk_margin": _json(mg.loop_disk_margin[i])}
                                    for i, a in enumerate(actuators)}
        return out


#: the summary's line per margin: label, format, and what an unlimited margin (inf, or 0 below) means
_SUMMARY = {"gain_margin": ("smallest gain margin", "x{:.4g}", "no gain above 1 destabilises"),
            "gain_margin_low": ("largest lower gain margin", "x{:.4g}", "no gain between 0 and 1 destabilises"),
            "phase_margin": ("smallest phase margin", "{:.4g} deg", "no loop's gain crosses 1"),
            "loop_disk_margin": ("smallest loop-at-a-time disk margin", "{:.4g}", "unlimited"),
            "disk_margin": ("smallest multiloop disk margin", "{:.4g}", "unlimited")}


def _json(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


@dataclass(frozen=True)
class RobustnessReport:
    """The outcome of :func:`check_robustness`.

    Attributes
    ----------
    controller : str
        The design's method.
    sample_rate : float
        [Hz]
    delay : bool
        Whether one sample of computation delay was in the loop.
    actuators : tuple of str
    uncertainty : Uncertainty
    cases : tuple of RobustnessCase
        Positions (outer) by parameter points (inner).
    """

    controller: str
    sample_rate: float
    delay: bool
    actuators: tuple[str, ...]
    uncertainty: Uncertainty
    cases: tuple[RobustnessCase, ...]

    @property
    def stable(self) -> bool:
        """Every case is stable."""
        return all(c.stable for c in self.cases)

    @property
    def worst(self) -> RobustnessCase:
        """The case with the largest spectral radius (the smallest stability margin ``1 - radius``)."""
        return max(self.cases, key=lambda c: c.spectral_radius)

    def worst_margin(self, name: str) -> RobustnessCase:
        """The stable case with the worst of one margin (:data:`MARGINS`; the worst spectral radius when
        no case has margins)."""
        if name not in MARGINS:
            raise ParameterError(f"name: must be one of {', '.join(MARGINS)}, got {name!r}")
        measured = [c for c in self.cases if c.margins is not None]
        if not measured:
            return self.worst
        return (min if MARGINS[name] else max)(measured, key=lambda c: c.margin(name))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the settings, ``stable``, ``worst`` (by spectral radius), ``worst_<margin>`` per margin
        and every case."""
        out: dict[str, Any] = {"controller": self.controller, "sample_rate": self.sample_rate, "delay": self.delay,
                               "uncertainty": self.uncertainty.to_dict(), "stable": self.stable,
                               "cases_checked": len(self.cases),
                               "unstable_cases": sum(not c.stable for c in self.cases),
                               "worst": self.worst.to_dict(self.actuators)}
        for name in MARGINS:
            out[f"worst_{name}"] = self.worst_margin(name).to_dict()
        out["cases"] = [c.to_dict(self.actuators) for c in self.cases]
        return out

    def summary(self) -> list[str]:
        """Text lines: the verdict, the worst spectral radius and the worst margin of each kind, with where."""
        w = self.worst
        n_bad = sum(not c.stable for c in self.cases)
        lines = [f"{self.controller} at {self.sample_rate:.4g} Hz{' with one sample of delay' if self.delay else ''}:"
                 f" {'stable' if not n_bad else 'UNSTABLE'} in {len(self.cases) - n_bad} of {len(self.cases)} cases",
                 f"largest spectral radius {w.spectral_radius:.5g} ({w.where})"]
        if not any(c.margins is not None for c in self.cases):
            return lines
        for name, (label, fmt, unlimited) in _SUMMARY.items():
            c = self.worst_margin(name)
            value = c.margin(name)
            lines.append(f"{label} {fmt.format(value)} ({c.where})" if 0.0 < value < math.inf else
                         f"{label}: none in any case ({unlimited})")
        return lines

    def raise_if_unstable(self) -> None:
        """Raise :class:`~isolator.errors.UnstableClosedLoopError` naming the worst unstable case (one line)."""
        if self.stable:
            return
        w = self.worst
        n_bad = sum(not c.stable for c in self.cases)
        raise UnstableClosedLoopError(
            f"the closed loop with {self.controller} is unstable with {w.where}: spectral radius "
            f"{w.spectral_radius:.4g} at {self.sample_rate:.4g} Hz sampling"
            f"{' with one sample of delay' if self.delay else ''}{', ' + w.growing if w.growing else ''} "
            f"({n_bad} of {len(self.cases)} cases unstable)")


def _growing(loop: SampledLoop) -> str:
    """``an oscillation at 441 Hz grows, from the open-loop mode 'plate 1' (442.3 Hz)``."""
    name, f_mode = loop.growing_mode()
    where = f"from the open-loop mode '{name}' ({f_mode:.4g} Hz)" if name != "none" else "from the controller's states"
    return f"an oscillation at {loop.frequency_hz:.4g} Hz grows, {where}"


def _configurations(scenario: Scenario, positions: Sequence[Mapping[str, float] | Sequence[float]] | None,
                    controller: DiscreteController | None = None) -> list[np.ndarray]:
    """The rest configurations to check (carriage coordinates [m], file order): given, or every combination of
    each carriage's extremes and middle, the start and the end; for a scheduled controller also the scheduling
    carriage halfway between neighbouring design points (where the matrices are interpolated)."""
    if positions is not None:
        if isinstance(positions, str | bytes | Mapping) or not len(positions):
            raise ParameterError("positions: must be a non-empty list of configurations (each by carriage name or "
                                 "one value per carriage)")
        return [rest_positions(scenario, p) for p in positions]
    out: list[np.ndarray] = []
    base = travel_configurations(scenario)[2:].tolist() + travel_configurations(scenario)[:2].tolist()
    extra = []
    if controller is not None and len(controller.schedule) > 1:
        c = controller.schedule_carriage
        points = [e.q[c] for e in controller.schedule]
        for q in base:
            for lo, hi in itertools.pairwise(points):
                extra.append([*q[:c], 0.5 * (lo + hi), *q[c + 1:]])
    for q in base + extra:
        if not any(np.allclose(q, seen, rtol=0.0, atol=1e-12) for seen in out):
            out.append(np.array(q, dtype=float))
    return out


def check_robustness(scenario: Scenario, controller: DiscreteController, uncertainty: Uncertainty | None = None,
                     positions: Sequence[Mapping[str, float] | Sequence[float]] | None = None,
                     progress: Callable[[int, int], object] | None = None, margins: bool = True
                     ) -> RobustnessReport:
    """Check ``controller``'s loop over the carriages' travel and the isolators' uncertainty.

    Parameters
    ----------
    scenario : Scenario
        With the controller's ``[[sensors]]`` and ``[[actuators]]`` (names in file order).
    controller : DiscreteController
        Scheduled controllers are taken at each configuration's positions (``matrices(q)``).
    uncertainty : Uncertainty, optional
        Default: none (the scenario's parameters only).
    positions : list of configurations, optional
        Rest configurations instead of the travel's: each by carriage name (the others at their start)
        or one value per carriage [m]. Default: every combination of each carriage's extremes and middle,
        the start and the end, and for a scheduled controller the scheduling carriage halfway between its
        design points.
    progress : callable, optional
        ``progress(done, total)`` after each case (e.g. to update a ``tqdm`` bar).
    margins : bool
        Compute the margins of the stable cases (False: the spectral radius only, about twice as fast).

    Returns
    -------
    RobustnessReport
        Call :meth:`~RobustnessReport.raise_if_unstable` to refuse an unstable design.

    Raises
    ------
    ParameterError
        The controller's names are not the scenario's; a named parameter the scenario lacks; a point of
        the uncertainty at which the passive table tips (one line naming the values and the positions).
    """
    uncertainty = Uncertainty() if uncertainty is None else uncertainty
    controller.check_names(scenario)
    configs = _configurations(scenario, positions, controller)
    layout = ParameterLayout.of(scenario)
    nominal = layout.pack(scenario)
    samples = uncertainty.samples()
    vectors = [uncertainty.parameters(layout, nominal, s) for s in samples]
    names = tuple(c.name for c in scenario.carriages)
    total, done, cases = len(configs) * len(samples), 0, []
    for q in configs:
        for values, p in zip(samples, vectors, strict=True):
            try:
                lin = linearise(scenario, positions=q, parameters=p)
            except UnstableTableError as error:
                key = "uncertainty" if values else "scenario"
                raise ParameterError(
                    f"{key}: {_describe_values(values)} tips the passive table with {_describe_positions(names, q)} "
                    f"(no stable equilibrium: {error})".replace("\n", " ")) from None
            loop = sampled_loop(lin, controller)
            radius = loop.spectral_radius
            found = None if radius >= 1.0 or not margins else sampled_margins(loop)
            cases.append(RobustnessCase(names, tuple(float(v) for v in q), tuple(values), radius, found,
                                        "" if loop.stable else _growing(loop)))
            done += 1
            if progress is not None:
                progress(done, total)
    return RobustnessReport(controller.method, controller.sample_rate, bool(controller.delay),
                            tuple(a.name for a in scenario.actuators), uncertainty, tuple(cases))


check_public(globals())
