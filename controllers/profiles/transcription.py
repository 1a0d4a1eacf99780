"""The run through the move that the profile optimisation differentiates: RK4 in phases, single or
multiple shooting.

The carriages' breakpoints, merged in the order of the starting design, cut
the move into **phases** in which every carriage is on one polynomial piece,
so each phase is smooth and its length is an expression of the design
parameters (the steps of a phase stretch with it). The exact model is
integrated by a compiled RK4 step through the phases; with multiple
shooting, the table's state at a node about every ``shooting_steps`` steps
is a variable too, tied to the run by a continuity constraint.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import casadi as ca
import numpy as np

from isolator.errors import ScenarioError
from isolator.model.equilibrium import air_in_groups, quasi_static_sensitivity
from isolator.model.parameters import ParameterLayout
from isolator.model.pneumatic_statics import air_function
from isolator.model.variants import Model
from isolator.numerics.native import NativeFunction
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.profile_shapes import segment_starts
from isolator.simulation.simulator import Simulator, get_model

from .move_design import MoveDesign

__all__ = [
    "MAX_PHASE_STEPS",
    "PEAK_POWER",
    "Nlp",
    "Phase",
    "Transcription",
    "VariantData",
    "advance",
    "carriage_state",
    "event_times",
    "move_phases",
    "variant_data",
]

#: most RK4 steps in one phase: a long cruise, where the table only follows the slow tilt, takes longer steps
MAX_PHASE_STEPS = 200

#: power of the p-norm standing in for each signal's peak (a smooth maximum)
PEAK_POWER = 16


# -- what each model variant contributes ------------------------------------------------------
@dataclass(frozen=True)
class VariantData:
    """Numbers of one model variant the symbolic problem needs."""

    parameters: np.ndarray
    start_state: np.ndarray
    final: np.ndarray  # (6,) final equilibrium signals
    omega_max: float  # fastest mode [rad/s]
    slowest_period: float  # [s]
    # pneumatic tables: the leveling table's quasi-static pose moves with each group's air,
    # final + air_sensitivity @ (air(x, p) - air_final) (isolator.model.equilibrium.quasi_static_sensitivity)
    air: ca.Function | None = None
    air_final: np.ndarray | None = None
    air_sensitivity: np.ndarray | None = None

    def reference(self, states: Any) -> Any:
        """The signals the table settles about, one column per state column (casadi): the final
        equilibrium, or for pneumatic tables the quasi-static pose of the air the state holds."""
        n = states.shape[1]
        final = ca.repmat(ca.DM(self.final), 1, n)
        if self.air is None or self.air_final is None or self.air_sensitivity is None:
            return final
        air = self.air.map(n)(states, ca.DM(self.parameters))
        return final + ca.DM(self.air_sensitivity) @ (air - ca.repmat(ca.DM(self.air_final), 1, n))


def variant_data(scenario: Scenario) -> VariantData:
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
    data = VariantData(sim.parameters, start.state, final, float(np.max(np.abs(eig))), slowest)
    positions = scenario.final_positions()
    if sim.layout.pneumatic is None or positions is None:
        return data
    air = air_in_groups(sim.model, end.state[None, :], sim.parameters)[0]
    _, sensitivity = quasi_static_sensitivity(sim.model, sim.parameters, positions, air)
    return replace(data, air=air_function(sim.layout), air_final=air, air_sensitivity=sensitivity)


# -- phases ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Phase:
    """A stretch of the move in which each carriage is on one piece."""

    first: tuple[int, int]  # (carriage, event) opening it
    last: tuple[int, int]  # (carriage, event) closing it
    pieces: tuple[int, ...]  # per carriage: -1 before its start, n_segments after its stop
    steps: int


def event_times(designs: Sequence[MoveDesign], values: Sequence[Any]) -> list[list[Any]]:
    """Per carriage: start, then the end of each segment."""
    out = []
    for d, v in zip(designs, values, strict=True):
        times = [v[0]]
        for seg in d.segments(v):
            times.append(times[-1] + seg.duration)
        out.append(times)
    return out


def move_phases(designs: Sequence[MoveDesign], steps_for: Callable[[float], int]) -> list[Phase]:
    """The move's phases, in the order of the designs' own event times."""
    times = event_times(designs, [d.values for d in designs])
    events = sorted(((float(t), i, k) for i, ts in enumerate(times) for k, t in enumerate(ts)))
    seen = [0] * len(designs)
    out = []
    for (t_lo, i, k), (t_hi, j, m) in itertools.pairwise(events):
        seen[i] += 1
        pieces = tuple(s - 1 for s in seen)
        out.append(Phase((i, k), (j, m), pieces, steps_for(t_hi - t_lo)))
    return out


def carriage_state(design: MoveDesign, values: Any) -> list[tuple[Any, Any, Any, Any]]:
    """(q, v, a, jerk) at the start of each segment, then at rest at the end."""
    segs = design.segments(values)
    starts = segment_starts(design.start, [g.duration for g in segs], [g.acceleration for g in segs],
                            [g.jerk for g in segs])
    out = [(q, v, g.acceleration, g.jerk) for (q, v), g in zip(starts, segs, strict=False)]
    out.append((design.start + design.stroke, 0.0, 0.0, 0.0))
    return out



# -- the problem's lists ---------------------------------------------------------------------------
@dataclass
class Nlp:
    """The NLP's variables, their bounds and start, and its constraints with their bounds, as built up."""

    variables: list[ca.MX]
    lbx: list[float] = field(default_factory=list)
    ubx: list[float] = field(default_factory=list)
    x0: list[float] = field(default_factory=list)
    g: list[Any] = field(default_factory=list)
    lbg: list[float] = field(default_factory=list)
    ubg: list[float] = field(default_factory=list)


# -- the run through the move ------------------------------------------------------------------
class Transcription:
    """The exact model run by RK4 through the phases of one design structure.

    Parameters
    ----------
    scenario : Scenario
    designs : tuple of MoveDesign
    phases : sequence of Phase
    events : list of list
        Per carriage, its event times as expressions of the design parameters
        (:func:`event_times` of the symbolic values).
    states : list of list
        Per carriage, :func:`carriage_state` of the symbolic values.
    peaks : ndarray (6,)
        Each signal's peak in the baseline run (the scale of the smooth peaks and the states).
    shooting_steps : int
        RK4 steps per shooting interval.
    """

    def __init__(self, scenario: Scenario, designs: Sequence[MoveDesign], phases: Sequence[Phase],
                 events: list[list[Any]], states: list[list[tuple[Any, Any, Any, Any]]], peaks: np.ndarray,
                 shooting_steps: int) -> None:
        self.layout = ParameterLayout.of(scenario)
        self.model = get_model(self.layout, "exact")
        self.designs = designs
        self.phases = phases
        self.events = events
        self.states = states
        self.peaks = peaks
        self.shooting_steps = shooting_steps
        self.step_fn = step_function(self.model, self.layout, len(designs))
        self.sense = sense_function(self.model)
        #: each phase's length, an expression of the design parameters
        self.lengths = [events[ph.last[0]][ph.last[1]] - events[ph.first[0]][ph.first[1]] for ph in phases]

    def trajectory(self, vd: VariantData, nlp: Nlp | None) -> tuple[Any, Any, Any, list[Any]]:
        """Integrate one variant through the phases.

        Returns the state at the stop, each signal's sum of ``(s / peak0)^PEAK_POWER``
        and its largest ``|s| / peak0`` over the steps, and the state at the end of each
        shooting interval. With ``nlp`` (multiple shooting) each interval starts from a new variable.
        """
        n = len(self.designs)
        x: Any = ca.DM(vd.start_state)
        ref = ca.DM(vd.start_state)
        scale_peak = ca.DM(self.peaks)
        power: Any = ca.DM.zeros(6, 1)
        hard: Any = ca.DM.zeros(6, 1)
        ends = []
        state_scale = ca.DM(self.state_scale(vd))
        chunk_steps = self.shooting_steps
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
                xs = advance(self.step_fn, chunk, x, taus, h, coef_m, vd.parameters)
                e = self.sense.map(chunk)(xs, ca.repmat(ref, 1, chunk))[:6, :] / ca.repmat(scale_peak, 1, chunk)
                power = power + ca.sum2(e**PEAK_POWER)
                hard = ca.fmax(hard, ca.vertcat(*[ca.mmax(ca.fabs(e[r, :])) for r in range(6)]))
                x = xs[:, -1]
                ends.append(x)
                done += chunk
                if nlp is not None:
                    x = shooting_node(x, vd.start_state, state_scale, nlp)
        return x, power, hard, ends

    def state_scale(self, vd: VariantData) -> np.ndarray:
        """Typical size of each state's deviation: the baseline peaks, rates at the slowest mode."""
        omega = 2 * math.pi / vd.slowest_period
        trans, rot = float(np.max(self.peaks[:3])), float(np.max(self.peaks[3:]))
        if self.model.n_states == 13:  # position, quaternion, velocity, body rate
            return np.array([trans] * 3 + [rot / 2] * 4 + [trans * omega] * 3 + [rot * omega] * 3)
        return np.array([trans] * 3 + [rot] * 3 + [trans * omega] * 3 + [rot * omega] * 3)


# -- pieces ----------------------------------------------------------------------------------
def step_function(model: Model, layout: ParameterLayout, n: int) -> ca.Function:
    """One RK4 step: (x, tau (n,), h, coef (n, 4), p) -> x, expanded to scalar operations, compiled."""
    nx, nc = model.n_states, layout.input_size
    x = ca.MX.sym("x", nx)
    tau = ca.MX.sym("tau", n)
    h = ca.MX.sym("h")
    coef = ca.MX.sym("coef", n, 4)
    p = ca.MX.sym("p", layout.size)

    def inputs(t: ca.MX) -> ca.MX:
        q0, v0, a0, j = coef[:, 0], coef[:, 1], coef[:, 2], coef[:, 3]
        q = q0 + v0 * t + a0 * t**2 / 2 + j * t**3 / 6
        v = v0 + a0 * t + j * t**2 / 2
        a = a0 + j * t
        return ca.vertcat(q, v, a, ca.MX.zeros(nc - 3 * n, 1))

    c0, c1, c2 = inputs(tau), inputs(tau + h / 2), inputs(tau + h)
    k1 = model.rhs(x, c0, p)
    k2 = model.rhs(x + h / 2 * k1, c1, p)
    k3 = model.rhs(x + h / 2 * k2, c1, p)
    k4 = model.rhs(x + h * k3, c2, p)
    name = f"profile_rk4_{model.tag}"
    step = ca.Function(name, [x, tau, h, coef, p], [x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)]).expand()
    return compiled(step)


def sense_function(model: Model) -> ca.Function:
    """The six sensed signals from the state and the reference state, compiled."""
    x = ca.MX.sym("x", model.n_states)
    ref = ca.MX.sym("ref", model.n_states)
    sense = ca.Function(f"profile_sense_{model.kind}", [x, ref], [model.variant.sensed_motion(x, ref)])
    return compiled(sense.expand())


def compiled(function: ca.Function) -> ca.Function:
    """The function compiled (cached on disk) with its first derivatives, as a casadi function."""
    companions = (function.forward(1), function.reverse(1))
    return NativeFunction(function, companions=companions, optimisation="-O1").external()


def advance(step_fn: ca.Function, steps: int, x: Any, taus: Any, h: Any, coef: Any, p: np.ndarray) -> Any:
    """States after each of ``steps`` RK4 steps, (n_states, steps)."""
    acc = step_fn.mapaccum(steps)
    return acc(x, taus, ca.repmat(h, 1, steps), ca.repmat(coef, 1, steps), ca.repmat(ca.DM(p), 1, steps))


def shooting_node(x: Any, start: np.ndarray, scale: ca.DM, nlp: Nlp) -> ca.MX:
    """A new state variable (scaled about the start state) tied to ``x`` by a continuity constraint."""
    nx = int(scale.shape[0])
    node = ca.MX.sym(f"s{len(nlp.variables)}", nx)
    nlp.variables.append(node)
    nlp.lbx += [-math.inf] * nx
    nlp.ubx += [math.inf] * nx
    nlp.x0 += [0.0] * nx  # replaced by the starting design's run
    state = ca.DM(start) + scale * node
    nlp.g.append((x - state) / scale)
    nlp.lbg += [0.0] * nx
    nlp.ubg += [0.0] * nx
    return state


check_public(globals())
