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
apart), then a compass search on each world axis's velocity and angular velocity (by factors of 3, then of
sqrt(3)); skyhook's gain, the root locus's choice scaled on a coarse grid, then a compass search on each world
axis's actuators' gain (by factors of sqrt(2), then of 2^(1/4)). The compass search tries each weight down and
up from the best design so far and keeps stepping while the step pays; a sweep over the weights that finds
nothing better takes the square root of the factor, and the search ends when the factor passes its last value.
A candidate replaces the best only when it settles faster by more than :data:`TOLERANCE` of the passive
settling time (or as fast, with the signals' sum that much smaller): the settling time is a step function of
the weights (a signal that leaves its band once more settles a period later), so the coarse grid's factor of 3
steps over good designs a finer factor finds, and without the tolerance a weight that changes nothing would
drift to its extreme. A candidate that breaks a limit is left out; when none keeps them all the method's own
default stays.
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

__all__ = ["DISK_MARGIN", "FORCE_SHARE", "GAIN_MARGIN", "PHASE_MARGIN", "TOLERANCE", "TUNED", "Trial", "Tuning",
           "travel", "tune"]

#: the share of each actuator's ``max_force`` the move's peak command may use (room for what the model misses)
FORCE_SHARE = 0.8
#: the least loop-at-a-time gain margin over the travel [x]
GAIN_MARGIN = 2.0
#: the least loop-at-a-time phase margin over the travel [deg]
PHASE_MARGIN = 30.0
#: the least multiloop disk margin over the travel
DISK_MARGIN = 0.5
#: the least gain in settling time, as a share of the passive settling time, that makes a candidate the new best
TOLERANCE = 0.005
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
    best : Trial or None
        The chosen candidate (None: no candidate kept every limit).
    """

    settings: dict[str, Any]
    passive: float
    trials: list[Trial] = field(default_factory=list)
    best: Trial | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON: the choice, the passive settling, the limits and the number of candidates."""
        best = self.best
        passive = self.passive if math.isfinite(self.passive) else None
        return {"chosen": self.settings, "passive_settling": passive, "candidates": len(self.trials),
                "settling": None if best is None or not math.isfinite(best.settling) else best.settling,
                "force_share": FORCE_SHARE, "gain_margin": GAIN_MARGIN, "phase_margin": PHASE_MARGIN,
                "disk_margin": DISK_MARGIN}


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
    passive_time = _slowest(passive.settling_time)[0]
    tolerance = TOLERANCE * passive_time
    trials: list[Trial] = []
    best: list[Trial] = []

    def better(candidate: Trial) -> bool:
        """Whether ``candidate`` beats the best so far by more than the tolerance (see the module)."""
        if candidate.reason or not math.isfinite(candidate.settling):
            return False
        if not best:
            return True
        now = best[0]
        return candidate.settling < now.settling - tolerance or (
            candidate.settling <= now.settling and candidate.total < now.total - tolerance)

    seen: set[str] = set()

    def trial(settings: dict[str, Any]) -> bool:
        """Design, simulate and judge one candidate (recorded); True when it became the best. A candidate tried
        before is not tried again: it did not beat the best then, and the best has only improved."""
        name = repr({k: [f"{x:.9g}" for x in np.ravel(v)] for k, v in sorted(settings.items())})
        if name in seen:
            return False
        seen.add(name)
        try:
            ctrl = design(settings)
            run = sim.run(p=parameters, controller=ctrl)
        except IsolatorError as exc:
            trials.append(Trial(settings, math.inf, math.inf, math.inf, str(exc)))
            return False
        slowest, total = _slowest(run.with_band(band).settling_time)
        share = float(np.max(np.max(np.abs(run.actuator_forces), axis=1) / limits)) if limits.size else 0.0
        candidate = Trial(settings, slowest, total, share)
        if share > FORCE_SHARE:
            candidate = Trial(settings, slowest, total, share, f"peak command {share:.2f} of max_force")
        elif better(candidate):  # only a would-be best pays for the margins
            candidate = Trial(settings, slowest, total, share, _margins(scenario, ctrl))
        trials.append(candidate)
        if better(candidate):
            best[:] = [candidate]
            return True
        return False

    if method == "lqg":
        _search(trial, best, _lqg_start(), ("max_velocity", "max_rate"), (3.0, math.sqrt(3.0)))
    else:
        root_locus = design({}).settings["points"][0]["gain"]
        start = [{"gain": [root_locus * f] * 3} for f in (0.25, 0.5, 1.0, 2.0)]
        _search(trial, best, start, ("gain",), (math.sqrt(2.0), 2.0**0.25))
    if not best:
        return Tuning({}, passive_time, trials)
    return Tuning(dict(best[0].settings), passive_time, trials, best[0])


def _lqg_start() -> list[dict[str, Any]]:
    """The coarse grid: one acceptable velocity for all axes, the angular one equal or ten times larger."""
    return [{"max_velocity": [v] * 3, "max_rate": [v * k] * 3} for v in (1e-2, 3e-3, 1e-3, 3e-4) for k in (1, 10)]


def _search(trial: Callable[[dict[str, Any]], bool], best: list[Trial], start: list[dict[str, Any]],
            keys: tuple[str, ...], factors: tuple[float, ...]) -> None:
    """The coarse grid, then a compass search: each key's axes in turn down and up by the factor from the best so
    far, stepping on while a step pays (``trial`` says whether it did); a sweep that finds nothing better moves
    to the next of ``factors``."""
    for settings in start:
        trial(settings)
    level = 0
    while best and level < len(factors):
        factor, improved = factors[level], False
        for key in keys:
            for axis in range(3):
                for step in (1 / factor, factor):
                    moved = False
                    while _step(trial, best[0].settings, key, axis, step):
                        moved = True
                    if moved:
                        improved = True
                        break
        if not improved:
            level += 1


def _step(trial: Callable[[dict[str, Any]], bool], settings: dict[str, Any], key: str, axis: int,
          step: float) -> bool:
    """Try ``settings`` with ``key``'s value on ``axis`` times ``step``; True when that became the best."""
    values = list(settings[key])
    values[axis] *= step
    return trial({**settings, key: values})


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
