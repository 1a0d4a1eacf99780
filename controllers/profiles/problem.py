"""The profile optimisation's problem: its settings, and the NLP for one phase structure.

The design variables are each carriage's move parameters (start delay, cruise
speed, acceleration, deceleration, and jerk for an S-curve; see
:mod:`controllers.profiles.move_design`), scaled; the stroke is fixed. The
constraints: every segment at least zero long, the phases in the order of the
starting design (lengths >= 0) with each phase's step capped, every carriage
stopped within the move-time limit, and (multiple shooting) the continuity of
the runs at the nodes. ``objective="settling"`` minimises ``R + H``
(:mod:`controllers.profiles.objective`, averaged over the model variants);
``objective="cycle"`` minimises the move time with ``R + H`` at most
``residual_limit`` on every variant.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario

from .move_design import SHAPES, MoveDesign
from .move_metrics import ROBUSTNESS_VARIANTS, ModelVariant
from .objective import calibration, residual
from .transcription import (
    MAX_PHASE_STEPS,
    Nlp,
    Phase,
    Transcription,
    VariantData,
    carriage_state,
    event_times,
    move_phases,
)

__all__ = ["OBJECTIVES", "TRANSCRIPTIONS", "Problem", "ProfileSettings"]

OBJECTIVES = ("settling", "cycle")
TRANSCRIPTIONS = ("single", "multiple")


@dataclass(frozen=True)
class ProfileSettings:
    """Knobs of the profile optimisation.

    Attributes
    ----------
    objective : {"settling", "cycle"}
    transcription : {"single", "multiple"}
        Single shooting (the parameters only) or multiple shooting (the
        table's state at nodes about every ``shooting_steps`` steps too).
    shape : {"trapezoid", "scurve"} or None
        The profile shape designed (None: each carriage's own).
    max_move_time_increase : float
        Largest move time as a fraction over the baseline's (0.05: 5 % longer).
    variants : tuple of ModelVariant
        Models the objective is averaged over (and, for ``cycle``, each held to
        the residual limit); default: nominal, and isolator stiffness, damping
        and payload mass each 15 % off. The bands come from the nominal model.
    step_angle : float
        RK4 step times the fastest mode's angular frequency.
    window_periods : float
        Window after the stop, in periods of the slowest mode.
    band_margin : float
        ``H`` counts deviations beyond this fraction of the band.
    residual_limit : float
        Largest ``R + H`` for ``objective="cycle"`` (or the starting design's, if larger).
    shooting_steps : int
        RK4 steps per shooting interval (multiple shooting).
    screen : bool
        Before IPOPT, try braking phases timed to the periods of the modes each
        carriage excites most (by simulation) and start from the best; the
        objective has many local minima.
    max_iterations : int
    tolerance : float
        IPOPT's tolerance.
    """

    objective: str = "settling"
    transcription: str = "single"
    shape: str | None = "scurve"
    max_move_time_increase: float = 0.05
    variants: tuple[ModelVariant, ...] = ROBUSTNESS_VARIANTS
    step_angle: float = 0.25
    window_periods: float = 2.0
    band_margin: float = 0.5
    residual_limit: float = 0.05
    shooting_steps: int = 20
    screen: bool = True
    max_iterations: int = 100
    tolerance: float = 1e-6

    def __post_init__(self) -> None:
        self.check()

    def check(self) -> None:
        """Raise :class:`ParameterError` naming a bad setting (run on construction)."""
        for name in ("objective", "transcription"):
            if not isinstance(getattr(self, name), str):
                raise ParameterError(f"{name}: must be a string, got {getattr(self, name)!r}")
        if self.shape is not None and self.shape not in SHAPES:
            raise ParameterError(f"shape: must be one of {', '.join(SHAPES)} or None, got {self.shape!r}")
        if not isinstance(self.screen, bool):
            raise ParameterError(f"screen: must be True or False, got {self.screen!r}")
        if not isinstance(self.variants, tuple | list) or not all(
                isinstance(v, ModelVariant) for v in self.variants):
            raise ParameterError(f"variants: must be a sequence of ModelVariant, got {self.variants!r}")
        for name in ("max_move_time_increase", "step_angle", "window_periods", "band_margin", "residual_limit",
                     "tolerance"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
                raise ParameterError(f"{name}: must be a number, got {value!r}")
        for name in ("shooting_steps", "max_iterations"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise ParameterError(f"{name}: must be a whole number >= 1, got {value!r}")
        if self.objective not in OBJECTIVES:
            raise ParameterError(f"objective: must be one of {', '.join(OBJECTIVES)}, got '{self.objective}'")
        if self.transcription not in TRANSCRIPTIONS:
            raise ParameterError(
                f"transcription: must be one of {', '.join(TRANSCRIPTIONS)}, got '{self.transcription}'"
            )
        if not (math.isfinite(self.max_move_time_increase) and self.max_move_time_increase >= 0):
            raise ParameterError(
                f"max_move_time_increase: must be a finite fraction >= 0, got {self.max_move_time_increase}"
            )
        if not self.variants:
            raise ParameterError("variants: need at least one model")
        for name in ("step_angle", "window_periods", "band_margin", "residual_limit", "tolerance"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ParameterError(f"{name}: must be a finite number > 0, got {value}")


class Problem:
    """The NLP for a fixed phase structure.

    Parameters
    ----------
    scenario : Scenario
    designs : tuple of MoveDesign
        The starting design.
    settings : ProfileSettings
    data : list of VariantData
        Per model variant.
    peaks : ndarray (6,)
        The baseline's peaks (:func:`controllers.profiles.objective.peak_floor`).
    command : float
        When the move is commanded [s]: no carriage starts before.
    max_move : float
        Longest move [s] from the command.
    phases : sequence of Phase, optional
        An earlier problem's phases: their steps are kept when the structure is the same.
    """

    def __init__(
        self,
        scenario: Scenario,
        designs: tuple[MoveDesign, ...],
        settings: ProfileSettings,
        data: list[VariantData],
        peaks: np.ndarray,
        command: float,
        max_move: float,
        phases: Sequence[Phase] | None = None,
    ) -> None:
        self.scenario = scenario
        self.designs = designs
        self.settings = settings
        self.peaks = peaks
        self.step = settings.step_angle / max(d.omega_max for d in data)
        self.phases = move_phases(designs, lambda length: min(MAX_PHASE_STEPS, max(8, math.ceil(length / self.step))))
        if phases is not None and [(p.first, p.last, p.pieces) for p in phases] == [
                (p.first, p.last, p.pieces) for p in self.phases]:
            self.phases = list(phases)  # an earlier problem's steps, so that its solver point fits
        # the largest step a phase may stretch to: three nominal steps, or half as long again as it starts
        times = event_times(designs, [d.values for d in designs])
        self.caps = [
            max(3.0 * self.step, 1.5 * float(times[ph.last[0]][ph.last[1]] - times[ph.first[0]][ph.first[1]])
                / ph.steps)
            for ph in self.phases
        ]
        sizes = [len(d.names) for d in designs]
        self.theta = ca.MX.sym("theta", sum(sizes))
        self.n_theta = int(self.theta.shape[0])
        self.scales = np.concatenate([d.scales for d in designs])
        values, at = [], 0
        for size in sizes:
            values.append([self.theta[at + k] * self.scales[at + k] for k in range(size)])
            at += size
        #: the run through the move, its times and the carriages' states expressions of ``theta``
        self.run = Transcription(scenario, designs, self.phases, event_times(designs, values),
                                 [carriage_state(d, v) for d, v in zip(designs, values, strict=True)], peaks,
                                 settings.shooting_steps)
        self.window = settings.window_periods * max(d.slowest_period for d in data)
        nlp = Nlp([self.theta])
        variables, lbx, ubx, x0, g, lbg, ubg = nlp.variables, nlp.lbx, nlp.ubx, nlp.x0, nlp.g, nlp.lbg, nlp.ubg

        # design bounds: positive parameters within the limits; starts not before the command
        for d in designs:
            lo = 1e-3 * d.scales
            lo[0] = command
            lbx += list(lo / d.scales)
            ubx += list(d.upper / d.scales)
            x0 += list(d.values / d.scales)
        # every segment at least zero long
        for d, v in zip(designs, values, strict=True):
            for seg in d.segments(v):
                g.append(seg.duration)
                lbg.append(0.0)
                ubg.append(math.inf)
        # phases keep their order, and their steps stay below the cap
        for ph, cap, length in zip(self.phases, self.caps, self.run.lengths, strict=True):
            g.append(length)
            lbg.append(0.0)
            ubg.append(ph.steps * cap)
        # every carriage stopped within the move time
        move = None
        if settings.objective == "cycle":
            move = ca.MX.sym("move")
            variables.append(move)
            lbx.append(0.0)
            ubx.append(max_move)
            x0.append(max(d.stop_time() for d in designs) - command)
        for ev in self.run.events:
            g.append(ev[-1] - command - (0.0 if move is None else move))
            lbg.append(-math.inf)
            ubg.append(max_move if move is None else 0.0)

        theta0 = np.array(x0[: self.n_theta])
        factors = calibration(self.run, self.theta, data[0], theta0)
        residuals = []
        guesses = []
        for vd in data:
            if settings.transcription == "multiple":  # nodes start where the starting design puts the table
                _, _, _, ends = self.run.trajectory(vd, None)
                scale = self.run.state_scale(vd)
                guess = ca.Function("guess", [self.theta], [ca.vertcat(*[(e - vd.start_state) / scale for e in ends])])
                guesses.append(np.asarray(guess(theta0)).ravel())
            residuals.append(residual(self.run, vd, factors, nlp if settings.transcription == "multiple" else None,
                                      scenario.settling, self.window, self.step, settings.band_margin))
        mean_residual = sum(residuals) / len(residuals)
        x_all = ca.vertcat(*variables)
        self.x0 = np.array(x0, dtype=float)
        if guesses:
            first = self.n_theta + (move is not None)
            self.x0[first:] = np.concatenate(guesses)
        objective: Any
        if move is not None:
            # each model's residual within the limit, or within the starting design's (so that it is feasible)
            start = np.asarray(ca.Function("start", [x_all], [ca.vertcat(*residuals)])(self.x0)).ravel()
            g += residuals
            lbg += [-math.inf] * len(residuals)
            ubg += list(np.maximum(settings.residual_limit, start))
            objective = move / max_move
        else:
            objective = mean_residual
        self.nlp = {"x": x_all, "f": objective, "g": ca.vertcat(*g)}
        self.residual = ca.Function("residual", [x_all], [mean_residual])
        self.lbx, self.ubx = np.array(lbx, dtype=float), np.array(ubx, dtype=float)
        self.lbg, self.ubg = np.array(lbg, dtype=float), np.array(ubg, dtype=float)
        self.durations = ca.Function("durations", [self.theta], [ca.vertcat(*self.run.lengths)])
        #: what a solver point fits: the phases, their steps, the transcription and the objective
        self.structure = (tuple(self.phases), settings.transcription, settings.objective, len(data),
                          int(self.x0.size), int(self.lbg.size))


check_public(globals())
