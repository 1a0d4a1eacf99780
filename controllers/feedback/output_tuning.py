"""Default weights of the output-feedback designs, chosen by what the controller does on the scenario's move.

A design's weights trade damping against force and robustness, and the right trade depends on the table, the
move and the actuators. When they are not given, ``isolator controller`` (:func:`design_controller`) searches a
few of them and keeps the one whose closed loop settles the scenario's move fastest, judged by

* the move simulated with the controller in the loop (as ``isolator simulate --controller`` runs it), its
  settling time in the passive run's band (the slowest signal; the sum over signals breaks ties, which guides
  the search on the signals that are not the slowest yet);
* the actuators' force limits: the move's peak command at most :data:`FORCE_SHARE` of each ``max_force``;
* the robustness margins over the carriages' travel (nominal isolators): stable everywhere, loop-at-a-time
  gain margin at least :data:`GAIN_MARGIN`, phase margin at least :data:`PHASE_MARGIN` degrees, multiloop
  disk margin at least :data:`DISK_MARGIN`.

The search: LQG's acceptable velocities, one scale for all axes on a coarse grid (translations and rotations
apart), then each world axis's velocity and angular velocity in turn by factors of 3; skyhook's
gain, the root locus's choice scaled on a coarse grid, then each world axis's actuators' gain in turn by factors
of sqrt(2) (two passes; one that finds nothing better takes the square root of the factor). A candidate that
breaks a limit is left out; when none keeps them all the method's own default stays.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from isolator.errors import IsolatorError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.simulation.band import Band
from isolator.simulation.discrete_controller import DiscreteController
from isolator.simulation.simulator import Simulator

from .robustness import check_robustness

__all__ = ["DISK_MARGIN", "FORCE_SHARE", "GAIN_MARGIN", "PHASE_MARGIN", "TUNED", "Trial", "Tuning", "travel", "tune"]

#: the share of each actuator's ``max_force`` the move's peak command may use (room for what the model misses)
FORCE_SHARE = 0.8
#: the least loop-at-a-time gain margin over the travel [x]
GAIN_MARGIN = 2.0
#: the least loop-at-a-time phase margin over the travel [deg]
PHASE_MARGIN = 30.0
#: the least multiloop disk margin over the travel
DISK_MARGIN = 0.5
#: the settings each method's search chooses (giving any of them skips the search)
TUNED = {"lqg": ("max_velocity", "max_rate"), "skyhook": ("gain",)}


@dataclass(frozen=True)
class Trial:
    """One candidate's settings and how its loop did.

    Attributes
    ----------
    settings : dict
        The design's weights.
    settling : float
        The move's settling time in the passive band, slowest signal [s] (inf: a signal did not settle).
    total : float
        The sum of the signals' settling times [s].
    force_share : float
        The move's peak command over ``max_force`` (the largest over the actuators).
    reason : str
        Why it was left out ("" when it kept every limit).
    """

    settings: dict[str, Any]
    settling: float
    total: float
    force_share: float
    reason: str = ""

    @property
    def key(self) -> tuple[float, float]:
        """What the search minimises: the slowest signal's settling, then the sum."""
        return (self.settling, self.total) if not self.reason else (math.inf, math.inf)


@dataclass(frozen=True)
class Tuning:
    """A search's outcome.

    Attributes
    ----------
    settings : dict
        The chosen weights ({} when no candidate kept every limit: the method's own default).
    passive : float
        The passive table's settling time of the move [s].
    trials : list of Trial
        Every candidate, in the order tried.
    """

    settings: dict[str, Any]
    passive: float
    trials: list[Trial] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """JSON: the choice, the passive settling, the limits and the number of candidates."""
        best = min(self.trials, key=lambda t: t.key) if self.trials else None
        passive = self.passive if math.isfinite(self.passive) else None
        return {"chosen": self.settings, "passive_settling": passive, "candidates": len(self.trials),
                "settling": None if best is None or best.reason or not math.isfinite(best.settling)
                else best.settling, "force_share": FORCE_SHARE, "gain_margin": GAIN_MARGIN,
                "phase_margin": PHASE_MARGIN, "disk_margin": DISK_MARGIN}


def travel(scenario: Scenario) -> np.ndarray:
    """Each carriage's least and greatest position over the run [m], (carriages, 2), file order."""
    t_end = scenario.simulation.duration
    return np.array([c.profile.position_range(t_end) for c in scenario.carriages], dtype=float).reshape(-1, 2)


def _slowest(settling: dict[str, float | None]) -> tuple[float, float]:
    values = [math.inf if v is None else float(v) for v in settling.values()]
    return max(values), sum(values)


def tune(scenario: Scenario, method: str, design: Callable[[dict[str, Any]], DiscreteController],
         parameters: np.ndarray | None = None) -> Tuning:
    """Search ``method``'s weights for the scenario's move (see the module's description).

    Parameters
    ----------
    scenario : Scenario
        With ``[[sensors]]``, ``[[actuators]]`` and a move.
    method : {"lqg", "skyhook"}
    design : callable
        ``design(settings) -> DiscreteController``: the design with these weights (the rest as asked).
    parameters : ndarray, optional
        The model's parameter vector (default the scenario's).

    Returns
    -------
    Tuning
        Without a move (no carriage travels) or when the passive table does not settle within the run, no
        search: the method's own defaults.
    """
    ranges = travel(scenario)
    if not ranges.size or not np.any(ranges[:, 1] > ranges[:, 0]):
        return Tuning({}, math.nan, [])
    sim = Simulator(scenario)
    passive = sim.run(p=parameters)
    if not math.isfinite(_slowest(passive.settling_time)[0]):
        return Tuning({}, math.nan, [])
    band = Band.of_baseline("passive", passive.peak)
    limits = np.array([a.max_force for a in scenario.actuators])
    trials: list[Trial] = []
    best: list[Trial] = []

    def trial(settings: dict[str, Any]) -> Trial:
        try:
            ctrl = design(settings)
            run = sim.run(p=parameters, controller=ctrl)
        except IsolatorError as exc:
            return _record(trials, Trial(settings, math.inf, math.inf, math.inf, str(exc)))
        slowest, total = _slowest(run.with_band(band).settling_time)
        share = float(np.max(np.max(np.abs(run.actuator_forces), axis=1) / limits)) if limits.size else 0.0
        candidate = Trial(settings, slowest, total, share)
        if share > FORCE_SHARE:
            candidate = Trial(settings, slowest, total, share, f"peak command {share:.2f} of max_force")
        elif not best or candidate.key < best[0].key:  # only a would-be best pays for the margins
            reason = _margins(scenario, ctrl)
            candidate = Trial(settings, slowest, total, share, reason)
        if not candidate.reason and (not best or candidate.key < best[0].key):
            best[:] = [candidate]
        return _record(trials, candidate)

    if method == "lqg":
        _search(trial, best, _lqg_start(), ("max_velocity", "max_rate"), 3.0)
    else:
        root_locus = design({}).settings["points"][0]["gain"]
        start = [{"gain": [root_locus * f] * 3} for f in (0.25, 0.5, 1.0, 2.0)]
        _search(trial, best, start, ("gain",), math.sqrt(2.0))
    chosen = dict(best[0].settings) if best else {}
    return Tuning(chosen, _slowest(passive.settling_time)[0], trials)


def _record(trials: list[Trial], t: Trial) -> Trial:
    trials.append(t)
    return t


def _lqg_start() -> list[dict[str, Any]]:
    """The coarse grid: one acceptable velocity for all axes, the angular one equal or ten times larger."""
    return [{"max_velocity": [v] * 3, "max_rate": [v * k] * 3} for v in (1e-2, 3e-3, 1e-3, 3e-4) for k in (1, 10)]


def _search(trial: Callable[[dict[str, Any]], Trial], best: list[Trial], start: list[dict[str, Any]],
            keys: tuple[str, ...], factor: float, passes: int = 2) -> None:
    """The coarse grid, then each key's axes in turn by ``factor`` up and down from the best so far (a pass
    that finds nothing better halves the factor's logarithm)."""
    for settings in start:
        trial(settings)
    if not best:
        return
    for _ in range(passes):
        improved = False
        for key in keys:
            for axis in range(3):
                for step in (1 / factor, factor):
                    current = best[0]
                    values = list(current.settings[key])
                    values[axis] *= step
                    if trial({**current.settings, key: values}).key < current.key:
                        improved = True
                        break
        if not improved:
            factor = math.sqrt(factor)


def _margins(scenario: Scenario, ctrl: DiscreteController) -> str:
    """Why the loop fails the margins over the travel ("" when it keeps them)."""
    report = check_robustness(scenario, ctrl).to_dict()
    if not report["stable"]:
        return "unstable over the travel"
    gain = report["worst_gain_margin"]["gain_margin"]
    phase = report["worst_phase_margin"]["phase_margin"]
    disk = report["worst_disk_margin"]["disk_margin"]
    if gain is not None and gain < GAIN_MARGIN:
        return f"gain margin {gain:.3g}"
    if phase is not None and phase < PHASE_MARGIN:
        return f"phase margin {phase:.3g} deg"
    if disk is not None and disk < DISK_MARGIN:
        return f"disk margin {disk:.3g}"
    return ""


check_public(globals())
