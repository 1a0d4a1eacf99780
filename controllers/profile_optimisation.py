"""Carriage profiles optimised with casadi through the time-varying model.

The design variables are each carriage's move parameters (start delay, cruise
speed, acceleration, deceleration, and jerk for an S-curve; see
:mod:`controllers.move_design`); the stroke is fixed. The exact model is
integrated by RK4 through the move **in phases**: the carriages' breakpoints,
merged in the order of the starting design, cut the move into phases in which
every carriage is on one polynomial piece, so each phase is smooth and its
length is an expression of the parameters (the steps of a phase stretch with
it). The order is kept (phase lengths >= 0), and each phase's step is capped;
when a cap binds, the problem is rebuilt with more steps and solved again from
the answer (a warm start).

Objective (smooth, in units of the 5 % band of each signal):

* ``R``: the residual vibration at the stop, ``z' P z`` with ``z`` the table's
  deviation from its final equilibrium (six signals and rates, each divided by
  its band) and ``P`` from the Lyapunov equation of the model linearised at the
  final configuration, so ``R`` is the integral of the squared normalised
  deviation of the free response, divided by the slowest decay time;
* ``H``: over a window after the stop (integrated with the full model), the
  mean of ``max(0, (e / band)^2 - margin^2)^2``: the band, with a margin.

``objective="settling"`` minimises ``R + H`` (averaged over the model
variants) with the move at most ``max_move_time_increase`` longer than the
baseline's; ``objective="cycle"`` minimises the move time with ``R + H`` at
most ``residual_limit`` on every variant. Single or multiple shooting;
IPOPT (limited-memory Hessian). The true 5 % settling time is then measured by
the simulation.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from isolator.errors import OptimisationError, ScenarioError
from isolator.model.parameters import ParameterLayout
from isolator.numerics.native import NativeFunction
from isolator.scenario.definitions import SIGNALS, Scenario
from isolator.scenario.profile_shapes import segment_starts
from isolator.scenario.reader import resolve_scenario_path
from isolator.simulation.simulator import Simulator, get_model

from .input_shaping import ExcitedMode, dominant_modes
from .move_design import MoveDesign, command_time, move_designs, move_time
from .move_metrics import ROBUSTNESS_VARIANTS, ModelVariant, MoveMetrics, evaluate_move, with_moves

__all__ = [
    "OBJECTIVES",
    "TRANSCRIPTIONS",
    "ProfileOptimisation",
    "ProfileSettings",
    "optimise_profiles",
    "write_scenario",
]

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

    def check(self) -> None:
        """Raise :class:`ScenarioError` naming a bad setting."""
        if self.objective not in OBJECTIVES:
            raise ScenarioError(f"objective: must be one of {', '.join(OBJECTIVES)}, got '{self.objective}'")
        if self.transcription not in TRANSCRIPTIONS:
            raise ScenarioError(
                f"transcription: must be one of {', '.join(TRANSCRIPTIONS)}, got '{self.transcription}'"
            )
        if not (math.isfinite(self.max_move_time_increase) and self.max_move_time_increase >= 0):
            raise ScenarioError(
                f"max_move_time_increase: must be a finite fraction >= 0, got {self.max_move_time_increase}"
            )
        if not self.variants:
            raise ScenarioError("variants: need at least one model")
        for name in ("step_angle", "window_periods", "band_margin", "residual_limit", "tolerance"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ScenarioError(f"{name}: must be a finite number > 0, got {value}")
        for name in ("shooting_steps", "max_iterations"):
            if int(getattr(self, name)) < 1:
                raise ScenarioError(f"{name}: must be at least 1, got {getattr(self, name)}")


@dataclass(frozen=True)
class ProfileOptimisation:
    """An optimised move and how it compares with the baseline, by simulation.

    Attributes
    ----------
    designs : tuple of MoveDesign
        The optimised parameters per carriage.
    scenario : Scenario
        The scenario with the optimised profiles.
    baseline, optimised : MoveMetrics
        Measured by the true simulation (nominal model).
    objective, transcription : str
    status : str
        IPOPT's return status.
    iterations : int
        Summed over the rounds.
    rounds : int
        Solves (1, or more when a step cap was raised).
    build_time, solve_time : float
        Wall time [s] building the problems and solving them.
    objective_value : float
        ``R + H`` (mean over the variants) at the answer.
    warm_start : dict
        The solver's last primal and dual point, for :func:`optimise_profiles`'s ``warm_start``.
    """

    designs: tuple[MoveDesign, ...]
    scenario: Scenario
    baseline: MoveMetrics
    optimised: MoveMetrics
    objective: str
    transcription: str
    status: str
    iterations: int
    rounds: int
    build_time: float
    solve_time: float
    objective_value: float
    warm_start: dict[str, Any] = field(repr=False, compare=False)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (``baseline``, ``optimised``, ``designs``, solver facts)."""
        return {
            "objective": self.objective,
            "transcription": self.transcription,
            "baseline": self.baseline.to_dict(),
            "optimised": self.optimised.to_dict(),
            "designs": [
                {"carriage": d.name, "shape": d.shape, **dict(zip(d.names, map(float, d.values), strict=True))}
                for d in self.designs
            ],
            "solver": {"status": self.status, "iterations": self.iterations, "rounds": self.rounds,
                       "build_time": self.build_time, "solve_time": self.solve_time,
                       "objective_value": self.objective_value},
        }


# -- what each model variant contributes ------------------------------------------------------
@dataclass(frozen=True)
class _VariantData:
    """Numbers of one model variant the symbolic problem needs."""

    parameters: np.ndarray
    start_state: np.ndarray
    final: np.ndarray  # (6,) final equilibrium signals
    omega_max: float  # fastest mode [rad/s]
    slowest_period: float  # [s]


def _variant_data(scenario: Scenario) -> _VariantData:
    """Start state, final signals and time scales of one model."""
    sim = Simulator(scenario)
    start, end = sim.equilibria(sim.parameters)
    if end is None:  # cannot happen for trapezoids and S-curves
        raise ScenarioError("carriages: profile design needs moves that stop")
    final = sim.signals(end.state[None, :], start)[:, 0]
    eig = np.concatenate([start.eigenvalues, end.eigenvalues])
    eig = eig[np.abs(eig) > 1e-6 * np.max(np.abs(eig))]  # the quaternion's norm is no mode
    if np.max(eig.real) >= 0:
        raise ScenarioError("isolators: the table is not damped at rest; nothing settles")
    oscillating = np.abs(eig.imag)[np.abs(eig.imag) > 1e-6]
    slowest = float(2 * math.pi / oscillating.min()) if oscillating.size else float(1.0 / np.min(-eig.real))
    return _VariantData(sim.parameters, start.state, final, float(np.max(np.abs(eig))), slowest)


def _floors(values: np.ndarray) -> np.ndarray:
    """Per signal, 1e-3 of the largest value of its kind (translations, rotations); 1e-12 when all are 0."""
    tops = np.repeat([np.max(values[:3]), np.max(values[3:])], 3)
    return np.where(tops > 0, 1e-3 * tops, 1e-12)


def _peak_floor(peak: dict[str, float]) -> np.ndarray:
    """Each signal's peak [m, rad], floored at 1e-3 of the largest of its kind (a signal that
    symmetry keeps at zero must not dominate)."""
    values = np.array([peak[s] for s in SIGNALS], dtype=float)
    return np.maximum(values, _floors(values))


# -- phases ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Phase:
    """A stretch of the move in which each carriage is on one piece."""

    first: tuple[int, int]  # (carriage, event) opening it
    last: tuple[int, int]  # (carriage, event) closing it
    pieces: tuple[int, ...]  # per carriage: -1 before its start, n_segments after its stop
    steps: int


def _event_times(designs: Sequence[MoveDesign], values: Sequence[Any]) -> list[list[Any]]:
    """Per carriage: start, then the end of each segment."""
    out = []
    for d, v in zip(designs, values, strict=True):
        times = [v[0]]
        for seg in d.segments(v):
            times.append(times[-1] + seg.duration)
        out.append(times)
    return out


def _phases(designs: Sequence[MoveDesign], steps_for: Callable[[float], int]) -> list[_Phase]:
    """The move's phases, in the order of the designs' own event times."""
    times = _event_times(designs, [d.values for d in designs])
    events = sorted(((float(t), i, k) for i, ts in enumerate(times) for k, t in enumerate(ts)))
    seen = [0] * len(designs)
    phases = []
    for (t_lo, i, k), (t_hi, j, m) in itertools.pairwise(events):
        seen[i] += 1
        pieces = tuple(s - 1 for s in seen)
        phases.append(_Phase((i, k), (j, m), pieces, steps_for(t_hi - t_lo)))
    return phases


def _carriage_state(design: MoveDesign, values: Any) -> list[tuple[Any, Any, Any, Any]]:
    """(q, v, a, jerk) at the start of each segment, then at rest at the end."""
    segs = design.segments(values)
    starts = segment_starts(design.start, [g.duration for g in segs], [g.acceleration for g in segs],
                            [g.jerk for g in segs])
    out = [(q, v, g.acceleration, g.jerk) for (q, v), g in zip(starts, segs, strict=False)]
    out.append((design.start + design.stroke, 0.0, 0.0, 0.0))
    return out


# -- the symbolic problem ------------------------------------------------------------------------
#: most RK4 steps in one phase: a long cruise, where the table only follows the slow tilt, takes longer steps
MAX_PHASE_STEPS = 200

#: power of the p-norm standing in for each signal's peak (a smooth maximum)
PEAK_POWER = 16


class _Problem:
    """The NLP for a fixed phase structure.

    Each signal's band is ``fraction`` times its peak over the move, a smooth
    maximum (a ``PEAK_POWER``-norm over the RK4 steps, scaled to equal the true
    maximum at the starting design), so the objective sees that a gentler move
    also narrows the band of a signal that only its transients move.
    """

    def __init__(
        self,
        scenario: Scenario,
        designs: tuple[MoveDesign, ...],
        settings: ProfileSettings,
        data: list[_VariantData],
        peaks: np.ndarray,
        command: float,
        max_move: float,
        phases: Sequence[_Phase] | None = None,
    ) -> None:
        self.layout = ParameterLayout.of(scenario)
        self.model = get_model(self.layout, "exact")
        self.scenario = scenario
        self.designs = designs
        self.settings = settings
        self.peaks = peaks
        self.step = settings.step_angle / max(d.omega_max for d in data)
        self.phases = _phases(designs, lambda length: min(MAX_PHASE_STEPS, max(8, math.ceil(length / self.step))))
        if phases is not None and [(p.first, p.last, p.pieces) for p in phases] == [
                (p.first, p.last, p.pieces) for p in self.phases]:
            self.phases = list(phases)  # an earlier problem's steps, so that its solver point fits
        # the largest step a phase may stretch to: three nominal steps, or half as long again as it starts
        times = _event_times(designs, [d.values for d in designs])
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
        self.events = _event_times(designs, values)
        self.states = [_carriage_state(d, v) for d, v in zip(designs, values, strict=True)]
        self.step_fn = self._step_function(len(designs))
        self.sense = self._sense_function()
        self.window = settings.window_periods * max(d.slowest_period for d in data)
        nlp: tuple = ([self.theta], [], [], [], [], [], [])
        variables, lbx, ubx, x0, g, lbg, ubg = nlp

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
        self.lengths = []
        for ph, cap in zip(self.phases, self.caps, strict=True):
            length = self.events[ph.last[0]][ph.last[1]] - self.events[ph.first[0]][ph.first[1]]
            self.lengths.append(length)
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
        for ev in self.events:
            g.append(ev[-1] - command - (0.0 if move is None else move))
            lbg.append(-math.inf)
            ubg.append(max_move if move is None else 0.0)

        theta0 = np.array(x0[: self.n_theta])
        calibration = self._calibration(data[0], theta0)
        residuals = []
        guesses = []
        for vd in data:
            if settings.transcription == "multiple":  # nodes start where the starting design puts the table
                _, _, _, ends = self._trajectory(vd, None)
                scale = self._state_scale(vd)
                guess = ca.Function("guess", [self.theta], [ca.vertcat(*[(e - vd.start_state) / scale for e in ends])])
                guesses.append(np.asarray(guess(theta0)).ravel())
            residuals.append(self._residual(vd, calibration, nlp if settings.transcription == "multiple" else None))
        mean_residual = sum(residuals) / len(residuals)
        x_all = ca.vertcat(*variables)
        self.x0 = np.array(x0, dtype=float)
        if guesses:
            first = self.n_theta + (move is not None)
            self.x0[first:] = np.concatenate(guesses)
        if settings.objective == "cycle":
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
        self.durations = ca.Function("durations", [self.theta], [ca.vertcat(*self.lengths)])
        #: what a solver point fits: the phases, their steps, the transcription and the objective
        self.structure = (tuple(self.phases), settings.transcription, settings.objective, len(data),
                          int(self.x0.size), int(self.lbg.size))

    # -- the run through the move ------------------------------------------------------------------
    def _trajectory(self, vd: _VariantData, nlp: tuple | None) -> tuple[Any, Any, Any, list]:
        """Integrate one variant through the phases.

        Returns the state at the stop, each signal's sum of ``(s / peak0)^PEAK_POWER``
        and its largest ``|s| / peak0`` over the steps, and the state at the end of each
        shooting interval. With ``nlp`` (multiple shooting) each interval starts from a new variable.
        """
        n = len(self.designs)
        x = ca.DM(vd.start_state)
        ref = ca.DM(vd.start_state)
        scale_peak = ca.DM(self.peaks)
        power = ca.DM.zeros(6, 1)
        hard = ca.DM.zeros(6, 1)
        ends = []
        state_scale = ca.DM(self._state_scale(vd))
        chunk_steps = self.settings.shooting_steps
        for ph, length in zip(self.phases, self.lengths, strict=True):
            t_open = self.events[ph.first[0]][ph.first[1]]
            h = length / ph.steps
            coef, tau0 = [], []
            for i, piece in enumerate(ph.pieces):
                moving = 0 <= piece < len(self.states[i]) - 1
                coef.append(ca.horzcat(*(self.states[i][piece] if piece >= 0 else (self.designs[i].start, 0, 0, 0))))
                tau0.append(t_open - self.events[i][piece] if moving else 0.0)
            coef_m, tau0_v = ca.vertcat(*coef), ca.vertcat(*tau0)
            done = 0
            while done < ph.steps:
                chunk = min(chunk_steps, ph.steps - done)
                taus = ca.repmat(tau0_v, 1, chunk) + h * ca.repmat(ca.DM(np.arange(done, done + chunk)).T, n, 1)
                xs = _advance(self.step_fn, chunk, x, taus, h, coef_m, vd.parameters)
                e = self.sense.map(chunk)(xs, ca.repmat(ref, 1, chunk))[:6, :] / ca.repmat(scale_peak, 1, chunk)
                power = power + ca.sum2(e**PEAK_POWER)
                hard = ca.fmax(hard, ca.vertcat(*[ca.mmax(ca.fabs(e[r, :])) for r in range(6)]))
                x = xs[:, -1]
                ends.append(x)
                done += chunk
                if nlp is not None:
                    x = _shooting_node(x, vd.start_state, state_scale, nlp)
        return x, power, hard, ends

    def _calibration(self, vd: _VariantData, theta0: np.ndarray) -> np.ndarray:
        """Factors making the smooth peak equal the true one at the starting design."""
        _, power, hard, _ = self._trajectory(vd, None)
        fn = ca.Function("peaks", [self.theta], [power, hard])
        p, m = (np.asarray(v).ravel() for v in fn(theta0))
        smooth = p ** (1.0 / PEAK_POWER)
        return np.where(smooth > 0, m / np.where(smooth > 0, smooth, 1.0), 1.0)

    def _residual(self, vd: _VariantData, calibration: np.ndarray, nlp: tuple | None) -> ca.MX:
        """``R + H`` of one model variant: the window after the stop, in bands."""
        x, power, _, _ = self._trajectory(vd, nlp)
        peak = ca.DM(self.peaks * calibration) * power ** (1.0 / PEAK_POWER)
        floor = _floors(self.peaks)
        band = ca.vertcat(*[self.scenario.settling.band(s, ca.fmax(peak[i], floor[i])) for i, s in enumerate(SIGNALS)])
        n = len(self.designs)
        n_window = max(4, math.ceil(self.window / self.step))
        rest = ca.vertcat(*[ca.horzcat(st[-1][0], 0, 0, 0) for st in self.states])
        xs = _advance(self.step_fn, n_window, x, ca.DM.zeros(n, n_window), self.window / n_window, rest,
                      vd.parameters)
        zs = self.sense.map(n_window)(xs, ca.repmat(ca.DM(vd.start_state), 1, n_window))
        e = (zs[:6, :] - ca.repmat(ca.DM(vd.final), 1, n_window)) / ca.repmat(band, 1, n_window)
        over = ca.fmax(0, e**2 - self.settings.band_margin**2)
        return ca.sum1(ca.sum2(e**2 + over**2)) / n_window

    def _state_scale(self, vd: _VariantData) -> np.ndarray:
        """Typical size of each state's deviation: the baseline peaks, rates at the slowest mode."""
        omega = 2 * math.pi / vd.slowest_period
        trans, rot = float(np.max(self.peaks[:3])), float(np.max(self.peaks[3:]))
        if self.model.n_states == 13:  # position, quaternion, velocity, body rate
            return np.array([trans] * 3 + [rot / 2] * 4 + [trans * omega] * 3 + [rot * omega] * 3)
        return np.array([trans] * 3 + [rot] * 3 + [trans * omega] * 3 + [rot * omega] * 3)

    # -- pieces ----------------------------------------------------------------------------------
    def _step_function(self, n: int) -> ca.Function:
        """One RK4 step: (x, tau (n,), h, coef (n, 4), p) -> x, expanded to scalar operations."""
        nx, nc = self.model.n_states, self.layout.input_size
        x = ca.MX.sym("x", nx)
        tau = ca.MX.sym("tau", n)
        h = ca.MX.sym("h")
        coef = ca.MX.sym("coef", n, 4)
        p = ca.MX.sym("p", self.layout.size)

        def inputs(t: ca.MX) -> ca.MX:
            q0, v0, a0, j = coef[:, 0], coef[:, 1], coef[:, 2], coef[:, 3]
            q = q0 + v0 * t + a0 * t**2 / 2 + j * t**3 / 6
            v = v0 + a0 * t + j * t**2 / 2
            a = a0 + j * t
            return ca.vertcat(q, v, a, ca.MX.zeros(nc - 3 * n, 1))

        c0, c1, c2 = inputs(tau), inputs(tau + h / 2), inputs(tau + h)
        k1 = self.model.rhs(x, c0, p)
        k2 = self.model.rhs(x + h / 2 * k1, c1, p)
        k3 = self.model.rhs(x + h / 2 * k2, c1, p)
        k4 = self.model.rhs(x + h * k3, c2, p)
        name = f"profile_rk4_{self.model.tag}"
        step = ca.Function(name, [x, tau, h, coef, p], [x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)]).expand()
        return _compiled(step)

    def _sense_function(self) -> ca.Function:
        x = ca.MX.sym("x", self.model.n_states)
        ref = ca.MX.sym("ref", self.model.n_states)
        sense = ca.Function(f"profile_sense_{self.model.kind}", [x, ref], [self.model.variant.sensed_motion(x, ref)])
        return _compiled(sense.expand())


def _compiled(function: ca.Function) -> ca.Function:
    """The function compiled (cached on disk) with its first derivatives, as a casadi function."""
    companions = (function.forward(1), function.reverse(1))
    return NativeFunction(function, companions=companions, optimisation="-O1").external()


def _advance(step_fn: ca.Function, steps: int, x: Any, taus: Any, h: Any, coef: Any, p: np.ndarray) -> Any:
    """States after each of ``steps`` RK4 steps, (n_states, steps)."""
    acc = step_fn.mapaccum(steps)
    return acc(x, taus, ca.repmat(h, 1, steps), ca.repmat(coef, 1, steps), ca.repmat(ca.DM(p), 1, steps))


def _shooting_node(x: Any, start: np.ndarray, scale: ca.DM, nlp: tuple) -> ca.MX:
    """A new state variable (scaled about the start state) tied to ``x`` by a continuity constraint."""
    variables, lbx, ubx, x0, g, lbg, ubg = nlp
    nx = int(scale.shape[0])
    node = ca.MX.sym(f"s{len(variables)}", nx)
    variables.append(node)
    lbx += [-math.inf] * nx
    ubx += [math.inf] * nx
    x0 += [0.0] * nx  # replaced by the starting design's run
    state = start + scale * node
    g.append((x - state) / scale)
    lbg += [0.0] * nx
    ubg += [0.0] * nx
    return state


# -- solving ---------------------------------------------------------------------------------------
class _Monitor(ca.Callback):
    """IPOPT's iterations: progress lines and the best feasible point seen."""

    def __init__(self, problem: _Problem, progress: bool, tolerance: float) -> None:
        ca.Callback.__init__(self)
        self.n_x, self.n_g = problem.nlp["x"].shape[0], problem.nlp["g"].shape[0]
        self.lbg, self.ubg = problem.lbg, problem.ubg
        self.lbx, self.ubx = problem.lbx, problem.ubx
        self.progress = progress
        self.tolerance = tolerance
        self.iteration = 0
        self.best: tuple[float, np.ndarray] | None = None
        self.construct("monitor", {})

    def get_n_in(self) -> int:
        return ca.nlpsol_n_out()

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return ca.nlpsol_out(i)

    def get_name_out(self, i: int) -> str:
        return "ret"

    def get_sparsity_in(self, i: int) -> ca.Sparsity:
        name = ca.nlpsol_out(i)
        if name == "f":
            return ca.Sparsity.scalar()
        if name in ("x", "lam_x"):
            return ca.Sparsity.dense(self.n_x)
        if name in ("g", "lam_g"):
            return ca.Sparsity.dense(self.n_g)
        return ca.Sparsity(0, 0)

    def eval(self, arg: list) -> list:
        self.iteration += 1
        x = np.asarray(arg[0]).ravel()
        f = float(arg[1])
        g = np.asarray(arg[2]).ravel()
        violation = max(float(np.max(self.lbg - g, initial=0.0)), float(np.max(g - self.ubg, initial=0.0)),
                        float(np.max(self.lbx - x, initial=0.0)), float(np.max(x - self.ubx, initial=0.0)))
        if violation <= self.tolerance and (self.best is None or f < self.best[0]):
            self.best = (f, x.copy())
        if self.progress and self.iteration % 10 == 0:
            print(f"  iteration {self.iteration}: objective {f:.4g}, constraint violation {violation:.2g}", flush=True)
        return [0]


_SUCCESS = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


def optimise_profiles(
    scenario: Scenario,
    settings: ProfileSettings | None = None,
    warm_start: ProfileOptimisation | None = None,
    progress: bool = False,
) -> ProfileOptimisation:
    """Optimise the carriages' profiles to cut the settling (or cycle) time.

    Parameters
    ----------
    scenario : Scenario
        Its carriages' trapezoids or S-curves are the baseline and the
        starting design; their ``limits`` bound the design.
    settings : ProfileSettings, optional
    warm_start : ProfileOptimisation, optional
        Start from an earlier answer (its designs, and its solver point when
        the problem has the same shape).
    progress : bool
        Print a line every ten iterations.

    Returns
    -------
    ProfileOptimisation

    Raises
    ------
    ScenarioError
        Bad settings; carriages that are not trapezoids or S-curves; floor motion.
    OptimisationError
        IPOPT failed. The message gives its status; ``.result`` holds the best
        feasible point it reached (measured by simulation), or None.
    """
    settings = settings or ProfileSettings()
    settings.check()
    if scenario.ground is not None and scenario.ground.motion:
        raise ScenarioError("ground.motion: profile design needs a still floor")
    designs = move_designs(scenario, settings.shape)
    command = command_time(scenario)
    max_move = (1.0 + settings.max_move_time_increase) * move_time(scenario, command)
    baseline = evaluate_move(scenario, "baseline", command)
    if warm_start is not None:
        designs = _warm_designs(designs, warm_start.designs)
    designs = _within_move_time(designs, command, max_move)
    if warm_start is None and settings.screen:
        designs = _screened(scenario, designs, command, max_move, baseline, settings.objective, progress)
    peaks = _peak_floor(baseline.peak)
    data = [_variant_data(v.apply(scenario)) for v in settings.variants]
    if progress:
        print(f"optimising {len(designs)} carriages' {settings.shape or 'own'} profiles ({settings.objective}, "
              f"{settings.transcription} shooting, {len(data)} model(s))", flush=True)
    build = solve = 0.0
    iterations = rounds = 0
    point: dict[str, Any] | None = dict(warm_start.warm_start) if warm_start is not None else None
    status = "not run"
    value = math.nan
    for _ in range(4):
        rounds += 1
        t0 = time.perf_counter()
        earlier = point["structure"][0] if point is not None and "structure" in point else None
        problem = _Problem(scenario, designs, settings, data, peaks, command, max_move, earlier)
        monitor = _Monitor(problem, progress, 1e-6)
        options = {
            "ipopt.hessian_approximation": "limited-memory",
            "ipopt.limited_memory_max_history": 30,
            "ipopt.mu_strategy": "adaptive",
            "ipopt.max_iter": settings.max_iterations,
            "ipopt.tol": settings.tolerance,
            "ipopt.acceptable_tol": 1e3 * settings.tolerance,
            "ipopt.acceptable_obj_change_tol": 1e-4,
            "ipopt.acceptable_iter": 5,
            "ipopt.print_level": 0,
            "ipopt.sb": "yes",
            "print_time": False,
            "iteration_callback": monitor,
        }
        args = {"x0": problem.x0, "lbx": problem.lbx, "ubx": problem.ubx, "lbg": problem.lbg, "ubg": problem.ubg}
        if point is not None and point.get("structure") == problem.structure:
            # start at the earlier answer itself: IPOPT's default pushes it off its active bounds
            options.update({"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-6,
                            "ipopt.warm_start_bound_push": 1e-9, "ipopt.warm_start_bound_frac": 1e-9,
                            "ipopt.warm_start_slack_bound_push": 1e-9, "ipopt.warm_start_slack_bound_frac": 1e-9,
                            "ipopt.warm_start_mult_bound_push": 1e-9})
            args.update({"x0": point["x"], "lam_x0": point["lam_x"], "lam_g0": point["lam_g"]})
        solver = ca.nlpsol("profiles", "ipopt", problem.nlp, options)
        build += time.perf_counter() - t0
        t0 = time.perf_counter()
        out = solver(**args)
        solve += time.perf_counter() - t0
        stats = solver.stats()
        status = str(stats["return_status"])
        iterations += int(stats.get("iter_count", 0))
        x = np.asarray(out["x"]).ravel()
        point = {"x": x, "lam_x": np.asarray(out["lam_x"]).ravel(), "lam_g": np.asarray(out["lam_g"]).ravel(),
                 "structure": problem.structure}
        if status not in _SUCCESS:
            best = monitor.best[1] if monitor.best is not None else None
            result = None
            if best is not None:
                result = _result(scenario, problem, best, baseline, command, settings, status, iterations, rounds,
                                 build, solve, point)
            message = f"profile optimisation failed: IPOPT {status} after {iterations} iterations"
            if result is not None:
                message += (f"; best feasible point kept: settling {_fmt(result.optimised.settling_time_max)}, "
                            f"move {result.optimised.move_time:.3f} s")
            else:
                message += "; no feasible point was reached"
            error = OptimisationError(message)
            error.result = result  # type: ignore[attr-defined]
            raise error
        if monitor.best is not None and monitor.best[0] < float(out["f"]):
            x = monitor.best[1]  # IPOPT may stop at an acceptable point worse than one it passed
        value = float(problem.residual(x))
        designs = _designs_of(problem, x)
        lengths = np.asarray(problem.durations(x[: problem.n_theta])).ravel()
        caps = np.array([ph.steps * cap for ph, cap in zip(problem.phases, problem.caps, strict=True)])
        if np.all(lengths < 0.95 * caps):
            break
        # a phase outgrew its steps: more steps, from the answer (the warm start fits single shooting)
    return _result(scenario, problem, x, baseline, command, settings, status, iterations, rounds, build, solve,
                   point, value)


def _fmt(value: float | None) -> str:
    return "unavailable" if value is None else f"{value:.3f} s"


def _designs_of(problem: _Problem, x: np.ndarray) -> tuple[MoveDesign, ...]:
    """The designs at a solver point, held within their bounds (IPOPT may overstep them by its tolerance)."""
    n = problem.n_theta
    theta = np.clip(x[:n], problem.lbx[:n], problem.ubx[:n]) * problem.scales
    out, at = [], 0
    for d in problem.designs:
        out.append(d.with_values(theta[at: at + len(d.names)]))
        at += len(d.names)
    return tuple(out)


def _result(scenario: Scenario, problem: _Problem, x: np.ndarray, baseline: MoveMetrics, command: float,
            settings: ProfileSettings, status: str, iterations: int, rounds: int, build: float, solve: float,
            point: dict[str, Any] | None, value: float | None = None) -> ProfileOptimisation:
    designs = _designs_of(problem, x)
    optimised_scenario = with_moves(scenario, designs)
    optimised = evaluate_move(optimised_scenario, "optimised", command)
    return ProfileOptimisation(
        designs=designs, scenario=optimised_scenario, baseline=baseline, optimised=optimised,
        objective=settings.objective, transcription=settings.transcription, status=status,
        iterations=iterations, rounds=rounds, build_time=build, solve_time=solve,
        objective_value=float(problem.residual(x)) if value is None else value,
        warm_start=point or {},
    )


def _warm_designs(designs: tuple[MoveDesign, ...], previous: Sequence[MoveDesign]) -> tuple[MoveDesign, ...]:
    """The designs with an earlier answer's values where carriage and shape match."""
    by_name = {d.name: d for d in previous}
    return tuple(
        d.with_values(by_name[d.name].values) if d.name in by_name and by_name[d.name].shape == d.shape else d
        for d in designs
    )


def _within_move_time(designs: tuple[MoveDesign, ...], command: float, max_move: float) -> tuple[MoveDesign, ...]:
    """A starting design that ends within the move-time limit (an S-curve from a trapezoid runs longer).

    Speeds the slow carriages up within their limits, else leaves the design
    for IPOPT to repair. An answer that meets the limit within the solver's
    tolerance (a warm start) is kept as it is."""
    out = []
    for d in designs:
        if d.stop_time() - command > max_move * (1 + 1e-6) + 1e-9:
            lim = d.limits
            jerk = lim.jerk if d.shape == "scurve" else None
            d = replace(d, velocity=lim.velocity, acceleration=lim.acceleration, deceleration=lim.acceleration,
                        jerk=jerk, deceleration_jerk=jerk)
        out.append(d)
    return tuple(out)


def _screened(scenario: Scenario, designs: tuple[MoveDesign, ...], command: float, max_move: float,
              baseline: MoveMetrics, objective: str, progress: bool) -> tuple[MoveDesign, ...]:
    """The starting design with each carriage's braking timed to its excited modes' periods, where the
    simulation says that settles (or ends the cycle) sooner; one pass over the carriages."""
    peaks = list(baseline.peak.values())
    best = list(designs)
    best_score = _score(scenario, best, command, objective)
    tried = 0
    for i, d in enumerate(designs):
        modes = dominant_modes(scenario, i, peaks)[:3]
        for candidate in _braking_candidates(d, modes, command, max_move):
            trial = [*best[:i], candidate, *best[i + 1:]]
            score = _score(scenario, trial, command, objective)
            tried += 1
            if score < best_score:
                best, best_score = trial, score
    if progress:
        print(f"  screened {tried} braking timings: start from {objective} {best_score[0]:.3f} s", flush=True)
    return tuple(best)


def _score(scenario: Scenario, designs: Sequence[MoveDesign], command: float, objective: str) -> tuple[float, float]:
    """(settling or cycle time, move time) of a design by simulation; unknown settling counts as very long."""
    metrics = evaluate_move(with_moves(scenario, designs), "screen", command)
    settle = math.inf if metrics.settling_time_max is None else metrics.settling_time_max
    return (settle if objective == "settling" else settle + metrics.move_time, metrics.move_time)


def _braking_candidates(design: MoveDesign, modes: Sequence[ExcitedMode], command: float,
                        max_move: float) -> list[MoveDesign]:
    """Braking phases whose pulse has spectral zeros at the modes' damped periods.

    A trapezoid's braking is a rectangle of length ``T_d``: zeros at ``k / T_d``.
    An S-curve's is a rectangle of length ``T_j + T_c`` smoothed by one of
    length ``T_j``: zeros at ``k / (T_j + T_c)`` and ``k / T_j``.
    """
    lim = design.limits
    periods = [1.0 / (m.frequency * math.sqrt(1 - m.damping**2)) for m in modes]
    out = []
    for period in periods[:2]:
        for k in (1, 2, 3):
            plateau = k * period
            dec = design.velocity / plateau
            if dec > lim.acceleration:
                continue
            if design.shape == "trapezoid":
                out.append(replace(design, deceleration=dec))
                continue
            for ramp in {*(p for p in periods if p < plateau), plateau / 2}:
                jerk = dec / ramp
                if jerk <= lim.jerk:
                    out.append(replace(design, deceleration=dec, deceleration_jerk=jerk))
    return [c for c in out if c.fits() and c.stop_time() - command <= max_move]


def write_scenario(source: str | Path | None, designs: Sequence[MoveDesign], path: str | Path) -> Path:
    """Write a scenario file: the source file with each designed carriage's profile replaced.

    Parameters
    ----------
    source : str or Path or None
        The scenario file (or bundled name) the designs were made for.
    designs : sequence of MoveDesign
        Per carriage, by name.
    path : str or Path
        The file to write; it loads with :func:`isolator.load_scenario`.
        Relative ``file`` keys of the source are made absolute.
    """
    import tomllib

    import tomli_w

    origin = resolve_scenario_path(source)
    with open(origin, "rb") as handle:
        data = tomllib.load(handle)
    _absolute_files(data, origin.parent)
    by_name = {d.name: d for d in designs}
    for carriage in data.get("carriages", []):
        if carriage.get("name") in by_name:
            carriage["profile"] = by_name[carriage["name"]].profile().settings
    data["name"] = f"{data.get('name', origin.stem)}-optimised"
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    with open(target, "wb") as handle:
        tomli_w.dump(data, handle)
    return target


def _absolute_files(data: Any, base: Path) -> None:
    """Make every relative ``file`` key under ``data`` absolute (relative to ``base``)."""
    if isinstance(data, dict):
        for key, value in data.items():
            if key == "file" and isinstance(value, str) and not Path(value).is_absolute():
                data[key] = str((base / value).resolve())
            else:
                _absolute_files(value, base)
    elif isinstance(data, list):
        for item in data:
            _absolute_files(item, base)
