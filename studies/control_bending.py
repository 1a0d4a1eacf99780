"""The control study's bending-top case: the default sensor-based designs on the rigid and on the bending top.

``docs/scenario-format.md``, "Controllers on a bending top": every closed loop is judged on the plant with the
top's elastic modes. The case (:func:`run_bending_case`) shows what that changes, on a pair of scenarios that
differ only in their top (:func:`bending_pair`: a bending scenario and its rigid twin, or a rigid one and the
same table with the bundled granite top's six lowest elastic modes):

* each default design (``isolator controller``'s, by method) on each top: the move's settling in the study's
  band (simulated with the controller in the loop, the modes included on the bending top), the worst margins
  over the travel (:func:`controllers.feedback.check_robustness`) and the roll-off the bending top's design
  got (``settings["rolloff"]``); ``bending-defaults.png`` and a table in the report;
* the compliance at the corner of the top, open and closed loop on both tops (the error budget's loop,
  :class:`isolator.analysis.budget.loop.SourceResponses`, with a unit force at the point: the open loop is
  ``isolator compliance``'s curve); ``bending-compliance.png``;
* a stiff design (skyhook, :data:`STIFF_GAIN` N s/m, one sample of delay) made on the rigid top: stable there,
  refused by the check on the bending top (:func:`isolator.analysis.closed_loop.check_controller`), with the
  growing oscillation's frequency and the open-loop mode it comes from; and the same design made on the
  bending top, rolled off.

Quick (for tests and CI): skyhook only, the method's own gain (no search).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from controllers import feedback as fb
from isolator import Band, OptimisationError, ParameterError, Scenario, ScenarioError, Simulator
from isolator.analysis.budget.loop import SourceResponses
from isolator.analysis.budget.sources import Source
from isolator.analysis.closed_loop import SampledLoop, check_controller
from isolator.analysis.elastic_outputs import point_force_weights
from isolator.analysis.linear import LinearModel, linearise
from isolator.analysis.modes import modes
from isolator.model.equilibrium import DOF_NAMES
from isolator.scenario.actuators import Point
from isolator.scenario.arguments import check_public
from isolator.scenario.reader import load_scenario
from isolator.scenario.validation import validate_scenario
from isolator.simulation.discrete_controller import DiscreteController

__all__ = ["BENDING_TOP", "STIFF_GAIN", "TOPS", "BendingCase", "StiffDesign", "TopDesign", "bending_pair",
           "closed_loop_compliance", "run_bending_case"]

#: the bundled scenario whose top (its ``[table.flexible]``) a rigid 2 x 1 x 0.3 m, 4400 kg table gets
BENDING_TOP = "paper-table-3-2-flexible"
#: the stiff design's skyhook gain [N s/m] (with one sample of delay): stable on the rigid top, not on the bending
STIFF_GAIN = 6e4
#: the point whose compliance the case shows (added at the top face's +x +y corner when the scenario lacks it)
CORNER = "corner"
TOPS = ("rigid", "bending")


@dataclass(frozen=True)
class TopDesign:
    """One default design on one top.

    Attributes
    ----------
    method, top : str
        The design's method and ``rigid`` or ``bending``.
    controller : DiscreteController
        As ``isolator controller`` makes it on that top (``settings["rolloff"]`` when it was rolled off).
    settling : float or None
        The move's settling time, slowest signal, in the study's band [s] (None: not settled in the run).
    peak_force : float
        The move's largest actuator force [N].
    robustness : dict
        :meth:`controllers.feedback.RobustnessReport.to_dict` over the travel and the isolators' uncertainty.
    """

    method: str
    top: str
    controller: DiscreteController
    settling: float | None
    peak_force: float
    robustness: dict[str, Any]

    def margin(self, name: str) -> float:
        """The worst ``disk_margin``, ``gain_margin`` or ``phase_margin`` over the cases (nan: none, or
        unbounded)."""
        value = self.robustness[f"worst_{name}"][name] if self.robustness.get(f"worst_{name}") else None
        return math.nan if value is None else float(value)

    @property
    def rolloff_hz(self) -> float | None:
        """The roll-off's corner [Hz] (None: not rolled off)."""
        record = self.controller.settings.get("rolloff")
        return None if record is None else float(record["corner_hz"])

    def to_dict(self) -> dict[str, Any]:
        """JSON: settling, force, margins, spectral radius and roll-off."""
        return {"method": self.method, "top": self.top, "settling_time_max": self.settling,
                "peak_force": self.peak_force, "spectral_radius": self.robustness["worst"]["spectral_radius"],
                "disk_margin": _none(self.margin("disk_margin")), "gain_margin": _none(self.margin("gain_margin")),
                "phase_margin": _none(self.margin("phase_margin")), "rolloff": self.controller.settings.get("rolloff"),
                "gain": self.controller.settings.get("gain", self.controller.settings.get("points", [{}])[0]
                                                     .get("gain"))}


@dataclass(frozen=True)
class StiffDesign:
    """A stiff design made on the rigid top, checked on both, and the same design made on the bending top.

    Attributes
    ----------
    gain : float
        Skyhook's gain [N s/m] (one sample of delay).
    rigid, bending : SampledLoop
        The rigid top's design checked on each top (:func:`check_controller`, carriages at their start).
    mode : str
        The open-loop mode the bending top's growing oscillation comes from (as ``isolator modes`` names it).
    mode_hz : float
        That mode's frequency [Hz].
    rolled : DiscreteController
        The same design made on the bending top (rolled off: ``settings["rolloff"]``).
    rolled_loop : SampledLoop
        ``rolled`` checked on the bending top.
    """

    gain: float
    rigid: SampledLoop
    bending: SampledLoop
    mode: str
    mode_hz: float
    rolled: DiscreteController
    rolled_loop: SampledLoop

    def to_dict(self) -> dict[str, Any]:
        """JSON: the check on each top, the growing mode and the rolled-off design's check."""
        return {"gain": self.gain, "delay": True,
                "rigid": {"stable": self.rigid.stable, "spectral_radius": self.rigid.spectral_radius},
                "bending": {"stable": self.bending.stable, "spectral_radius": self.bending.spectral_radius,
                            "frequency_hz": self.bending.frequency_hz, "mode": self.mode,
                            "mode_frequency_hz": _none(self.mode_hz), "line": self.bending.describe()},
                "rolled_off": {"rolloff": self.rolled.settings.get("rolloff"), "stable": self.rolled_loop.stable,
                               "spectral_radius": self.rolled_loop.spectral_radius}}


@dataclass(frozen=True)
class BendingCase:
    """The bending-top case's results (see the module's description).

    Attributes
    ----------
    designs : tuple of TopDesign
        Each method on each top.
    frequency_hz : ndarray
        The compliance curves' frequencies [Hz] (below the controllers' Nyquist frequency).
    compliance : dict of str to ndarray
        ``"<top>, open"`` and ``"<top>, closed (<method>)"``: the corner's displacement per force along
        :attr:`axis` [m/N], complex.
    axis : str
    elastic_hz : dict of str to float
        The bending top's elastic modes on the isolators, by name [Hz].
    stiff : StiffDesign
    searched : bool
        Whether the designs' weights came from ``isolator controller``'s search (False: quick, the methods' own).
    left_out : dict of str to str
        Methods that could not be designed, with the reason.
    """

    designs: tuple[TopDesign, ...]
    frequency_hz: np.ndarray
    compliance: dict[str, np.ndarray]
    axis: str
    elastic_hz: dict[str, float]
    stiff: StiffDesign
    searched: bool
    left_out: dict[str, str]

    def design(self, method: str, top: str) -> TopDesign:
        """The design of ``method`` on ``top``."""
        return next(d for d in self.designs if d.method == method and d.top == top)

    def to_dict(self) -> dict[str, Any]:
        """JSON of the whole case (compliance as magnitudes [m/N])."""
        return {"designs": [d.to_dict() for d in self.designs], "searched": self.searched,
                "left_out": self.left_out, "elastic_modes_hz": self.elastic_hz,
                "compliance": {"point": CORNER, "axis": self.axis, "frequency_hz": self.frequency_hz.tolist(),
                               **{k: np.abs(v).tolist() for k, v in self.compliance.items()}},
                "stiff_design": self.stiff.to_dict()}


def _none(value: float) -> float | None:
    return None if not math.isfinite(value) else value


def _with_corner(scenario: Scenario) -> Scenario:
    """``scenario`` with a point ``corner`` on the top face's +x +y corner when it has none."""
    if any(p.name == CORNER for p in scenario.points) or scenario.table.size is None:
        return scenario
    lx, ly, lz = scenario.table.size
    return replace(scenario, points=(*scenario.points, Point(CORNER, (lx / 2, ly / 2, lz / 2))))


def bending_pair(scenario: Scenario) -> tuple[Scenario, Scenario]:
    """The rigid and the bending top of one table, each with a ``corner`` point.

    A scenario with ``[table.flexible]`` and its rigid twin (the top's six rigid modes are ``[table]``'s mass and
    inertia); a rigid scenario and the same with the top of :data:`BENDING_TOP` (its granite top's six lowest
    elastic modes, 178 to 653 Hz on the isolators), when its table is that top's size and mass.

    Raises
    ------
    ScenarioError
        No ``[[sensors]]`` or ``[[actuators]]``; a rigid table that is not the bundled top's (naming
        ``table.flexible``).
    """
    if not scenario.sensors or not scenario.actuators:
        raise ScenarioError("sensors: the bending-top case compares sensor-based designs and needs [[sensors]] "
                            "and [[actuators]]")
    scenario = _with_corner(scenario)
    if getattr(scenario.table, "flexible", None) is not None:
        return fb.rigid_top(scenario), scenario
    top = load_scenario(BENDING_TOP).table
    table = scenario.table
    same = table.size == top.size and table.mass == top.mass and np.allclose(table.inertia, top.inertia)
    if not same:
        raise ScenarioError(f"table.flexible: the control study's bending-top case needs the top's modes: give the "
                            f"scenario [table.flexible], or a table of {top.mass:g} kg and {top.size} m, whose "
                            f"bending top the bundled {BENDING_TOP} provides")
    return scenario, validate_scenario(replace(scenario, table=replace(table, flexible=top.flexible)))


def closed_loop_compliance(lin: LinearModel, point: str, axis: str, frequency_hz: np.ndarray,
                           controller: DiscreteController | None = None) -> np.ndarray:
    """The displacement of ``point`` along ``axis`` per unit force there along ``axis`` [m/N], complex, at
    ``frequency_hz`` (below the controller's Nyquist frequency): passive, or through the sampled loop of
    ``controller`` (the error budget's loop, :class:`SourceResponses`, with the point's force as its one
    source; passive, it is :func:`isolator.analysis.point_compliance.point_compliance`)."""
    target = next(p for p in lin.scenario.points if p.name == point)
    weights = point_force_weights(lin, target.position, np.eye(3)["xyz".index(axis)], target.feet,
                                  f"points ({point})")
    source = Source(f"force:{point}", np.ones_like, np.zeros(0), inputs=weights)
    return SourceResponses(lin, [source], [f"{point}:{axis}"], controller)(frequency_hz)[:, 0, 0]


def run_bending_case(scenario: Scenario, band: Band, sample_rate: float = 2000.0, quick: bool = False,
                     known: Mapping[str, DiscreteController] | None = None, axis: str = "z",
                     say: Callable[[str], None] | None = None) -> BendingCase:
    """Run the case on ``scenario``'s rigid and bending top (its figures and report section:
    :mod:`studies.control_bending_report`).

    Parameters
    ----------
    scenario : Scenario
        With ``[[sensors]]`` and ``[[actuators]]``; rigid or bending (:func:`bending_pair`).
    band : Band
        The study's settling band.
    sample_rate : float
        The designs' rate [Hz].
    quick : bool
        Skyhook only, with its own gain (no search).
    known : mapping, optional
        Designs already made on the rigid top, by method (the study's own sensor-based designs).
    axis : {"x", "y", "z"}
        Of the corner's compliance.
    say : callable, optional
        Progress lines.

    Returns
    -------
    BendingCase
    """
    say = say or (lambda text: None)
    tops = dict(zip(TOPS, bending_pair(scenario), strict=True))
    methods = ("skyhook",) if quick else fb.METHODS
    known = {} if quick else dict(known or {})
    designs, left_out, made = [], {}, {}
    for top, sc in tops.items():
        sim = Simulator(sc)
        for method in methods:
            say(f"bending-top case: {method} on the {top} top")
            try:
                ctrl = known[method] if top == "rigid" and method in known else \
                    fb.design_controller(sc, method, sample_rate, search=not quick)
            except (ParameterError, ScenarioError, OptimisationError) as exc:
                left_out[f"{method} ({top})"] = str(exc)
                continue
            run = sim.run(controller=ctrl)
            values = run.with_band(band).settling_time.values()
            settling = None if any(v is None for v in values) else max(v for v in values if v is not None)
            made[method, top] = ctrl
            designs.append(TopDesign(method, top, ctrl, settling, float(np.max(np.abs(run.actuator_forces))),
                                     fb.check_robustness(sc, ctrl).to_dict()))
    say("bending-top case: compliance at the corner and the stiff design")
    f = np.geomspace(1.0, 0.45 * sample_rate, 700)
    method = "skyhook" if ("skyhook", "bending") in made else next((m for m, _ in made), "")
    compliance = {}
    for top, sc in tops.items():
        lin = linearise(sc)
        compliance[f"{top}, open"] = closed_loop_compliance(lin, CORNER, axis, f)
        if (method, top) in made:
            compliance[f"{top}, closed ({method})"] = closed_loop_compliance(lin, CORNER, axis, f, made[method, top])
    table = modes(linearise(tops["bending"]))
    elastic = {n: float(fr) for n, fr in zip(table.dominant, table.frequencies_hz, strict=True) if n not in DOF_NAMES}
    case = BendingCase(tuple(designs), f, compliance, axis, elastic, _stiff(tops, sample_rate), not quick, left_out)
    return case


def _stiff(tops: Mapping[str, Scenario], sample_rate: float) -> StiffDesign:
    """The stiff skyhook made on the rigid top and checked on both; the same made on the bending top."""
    options = {"gain": STIFF_GAIN}
    ctrl = fb.design_controller(tops["rigid"], "skyhook", sample_rate, delay=True, options=options)
    bending = check_controller(tops["bending"], ctrl)
    mode, mode_hz = bending.growing_mode()
    rolled = fb.design_controller(tops["bending"], "skyhook", sample_rate, delay=True, options=options)
    return StiffDesign(STIFF_GAIN, check_controller(tops["rigid"], ctrl), bending, mode, mode_hz, rolled,
                       check_controller(tops["bending"], rolled))


check_public(globals())
