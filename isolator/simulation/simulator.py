"""Transient simulation of a scenario: from the initial equilibrium through the moves."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Literal, Protocol

import casadi as ca
import numpy as np

from isolator.errors import ScenarioError, SimulationError
from isolator.model.cache import get_model
from isolator.model.equilibrium import Equilibrium, static_equilibria
from isolator.model.parameters import ParameterLayout
from isolator.model.signals import signal_function
from isolator.model.variants import Model
from isolator.numerics.dop853 import DenseStepper, StepPlan, step_plan
from isolator.numerics.native import MappedFunction
from isolator.numerics.rk4 import Stepper
from isolator.scenario.definitions import Scenario
from isolator.scenario.profiles import SineProfile
from isolator.simulation.actuation import ForceHistory, applied_forces
from isolator.simulation.response import Response
from isolator.simulation.settling import SettlingResult, settling_metrics, signal_peaks
from isolator.simulation.time_grid import TimeGrid, grid_breakpoints, inputs_at, model_inputs, stage_times, time_grid

if TYPE_CHECKING:
    from isolator.simulation.batch import BatchResult

__all__ = [
    "FeedbackLaw",
    "Simulator",
    "simulate",
]

#: most the table may turn [rad] before a run is reported as diverged
MAX_TURN = 0.2
#: largest |lambda| h per RK4 step; keeps the relative error well below 1e-6
STEP_ANGLE = 0.05
#: largest |lambda| h per DOP853 step (Table 3.2: 2e-8 relative RMS at 0.9, 1e-7 with stiffness x2)
DENSE_STEP_ANGLE = 0.9
#: longest DOP853 step [s]; shorter ones come in ratios of 2^(1/8)
MAX_DENSE_STEP = 0.05

_STEPPERS: dict[tuple[ParameterLayout, str, int], Stepper] = {}
_DENSE: dict[tuple[ParameterLayout, str, int], DenseStepper] = {}


def _stepper(model: Model, substeps: int) -> Stepper:
    key = (model.layout, model.kind, substeps)
    if key not in _STEPPERS:
        _STEPPERS[key] = Stepper(model, substeps, model.variant.sensed_motion)
    return _STEPPERS[key]


def _dense_stepper(model: Model, lanes: int = 1) -> DenseStepper:
    key = (model.layout, model.kind, lanes)
    if key not in _DENSE:
        _DENSE[key] = DenseStepper(model, signal_function(model.variant, model.n_states), lanes)
    return _DENSE[key]


@lru_cache(maxsize=16)
def _staged_parameters(model: Model) -> np.ndarray:
    """Indices of the parameters the model's staged inputs depend on (none without a staged form)."""
    if model.staged_inputs is None:
        return np.zeros(0, dtype=int)
    c, p = model.staged_inputs.sx_in()
    v = model.staged_inputs(c, p)
    return np.array([i for i in range(p.shape[0]) if ca.depends_on(v, p[i])], dtype=int)


@lru_cache(maxsize=16)
def _staged_map(model: Model) -> MappedFunction:
    return MappedFunction(model.staged_inputs, f"isolator_staged_{model.tag}", block=256, optimisation="-O1")


@dataclass(frozen=True)
class Method:
    """How a run is integrated: DOP853 steps (``plan``) or RK4 on the sample grid (``substeps``)."""

    substeps: int
    plan: StepPlan | None = None
    plan_key: int = 0


class FeedbackLaw(Protocol):
    """A sampled controller the simulation runs (e.g. :class:`controllers.feedback.DiscreteLaw`).

    Attributes
    ----------
    sample_rate : float
        [Hz]; must divide the simulation's output sample rate.
    """

    sample_rate: float

    def reset(self) -> None:
        """Forget the controller's state (called at the start of a run)."""

    def __call__(self, t: float, measurement: np.ndarray) -> np.ndarray:
        """Commands [N] per actuator at tick ``t`` [s] from the measured table state (12,): displacement
        [m] and rotation vector [rad] from the initial equilibrium, velocity [m/s] and angular velocity
        [rad/s], world axes. Held until the next tick."""

    def final(self, passive: np.ndarray) -> np.ndarray:
        """The six signals' closed-loop final value given the passive one (the settling reference)."""


class Simulator:
    """A scenario's model built once, run many times.

    Parameters
    ----------
    scenario : Scenario
    model : {"exact", "paper"}
        The exact rigid-body model, or the paper's small-angle model.

    Examples
    --------
    >>> from isolator import load_scenario, Simulator
    >>> sim = Simulator(load_scenario("paper-table-3-2"))
    >>> response = sim.run()
    >>> response.settling_time_max  # doctest: +SKIP
    """

    def __init__(self, scenario: Scenario, model: str = "exact") -> None:
        self.scenario = scenario
        self.layout = ParameterLayout.of(scenario)
        self.model = get_model(self.layout, model)
        self.parameters = self.layout.pack(scenario)
        self.stop_time = scenario.stop_time
        settings = scenario.simulation
        self.grid: TimeGrid = time_grid(settings, scenario.breakpoints)
        self._breakpoints = grid_breakpoints(settings, scenario.breakpoints)
        self._longest_interval = float(np.max(np.diff(self.grid.nodes))) if self.grid.nodes.size > 1 else 0.0
        self._positions = (scenario.initial_positions(), scenario.final_positions())
        self._inputs: dict[int, np.ndarray] = {}
        self._plans: dict[int, StepPlan] = {}
        self._staged: dict[tuple[int, bytes], np.ndarray] = {}
        self._sample_inputs: np.ndarray | None = None
        drives = [c.profile for c in scenario.carriages]
        drives += list(scenario.ground.motion.values()) if scenario.ground is not None else []
        self._forcing = max((abs(d.omega) for d in drives if isinstance(d, SineProfile)), default=0.0)

    # -- parameters ------------------------------------------------------------
    def parameter_vector(self, changes: Mapping[str, float] | None = None) -> np.ndarray:
        """The parameter vector with named entries changed (names: ``layout.names``)."""
        p = self.parameters.copy()
        for name, value in (changes or {}).items():
            if name not in self.layout.names:
                raise ScenarioError(f"{name}: not a parameter of this scenario")
            if not math.isfinite(float(value)):
                raise ScenarioError(f"{name}: must be finite, got {value}")
            p[self.layout.names.index(name)] = float(value)
        return p

    def scaled_parameters(self, stiffness: float = 1.0, damping: float = 1.0) -> np.ndarray:
        """Parameter vector with all isolator stiffness and damping scaled."""
        return self.scaled_parameter_sets(stiffness, damping)[0]

    # -- pieces ----------------------------------------------------------------
    def equilibria(self, p: np.ndarray) -> tuple[Equilibrium, Equilibrium | None]:
        """Initial and final static equilibria (final None if a carriage never stops)."""
        start, end = self._equilibria(np.asarray(p, dtype=float)[None, :])
        return start[0], end[0]

    def _equilibria(self, params: np.ndarray) -> tuple[list[Equilibrium], list[Equilibrium | None]]:
        first, last = self._positions
        start = static_equilibria(self.model, params, first, "with the carriages at their start")
        if last is None:
            return start, [None] * len(start)
        return start, list(static_equilibria(self.model, params, last, "with the carriages at their final positions"))

    def substeps_for(self, omega_max: float) -> int:
        """RK4 steps per grid interval for a fastest eigenvalue ``omega_max`` [rad/s]."""
        omega = max(omega_max, self._forcing)
        return max(1, math.ceil(omega * self._longest_interval / STEP_ANGLE))

    def method_for(self, omega_max: float) -> Method:
        """The cheaper integration for a fastest eigenvalue ``omega_max`` [rad/s].

        DOP853 steps with |lambda| h <= ``DENSE_STEP_ANGLE`` between the breakpoints,
        unless breakpoints are so dense (sampled profiles) that RK4 on the sample
        grid costs fewer right-hand-side evaluations.
        """
        substeps = self.substeps_for(omega_max)
        omega = max(omega_max, self._forcing, 1e-12)
        key = max(0, math.ceil(8 * math.log2(MAX_DENSE_STEP * omega / DENSE_STEP_ANGLE)))
        if key not in self._plans:
            self._plans[key] = step_plan(self.grid.samples, self._breakpoints, MAX_DENSE_STEP * 2.0 ** (-key / 8))
        plan = self._plans[key]
        if plan.evaluations >= 4 * substeps * (self.grid.nodes.size - 1):
            return Method(substeps)
        return Method(substeps, plan, key)

    def _model_inputs(self, substeps: int) -> np.ndarray:
        if substeps not in self._inputs:
            self._inputs[substeps] = model_inputs(self.scenario, self.grid, substeps)
        return self._inputs[substeps]

    def _plan_inputs(self, method: Method, p: np.ndarray) -> np.ndarray:
        """The DOP853 stepper's inputs at every stage of the plan: the model's inputs, or their
        staged form (time-only moments; cached per carriage and table inertia)."""
        staged = self.model.staged_inputs
        uses = _staged_parameters(self.model)
        key = (method.plan_key, np.asarray(p, dtype=float)[uses].tobytes())
        if key not in self._staged:
            plan = method.plan
            inputs = inputs_at(self.scenario, *plan.stage_times())
            if staged is not None:
                flat = inputs.reshape(inputs.shape[0] * inputs.shape[1], inputs.shape[2])
                inputs = _staged_map(self.model)(flat, p)[0].reshape(*inputs.shape[:2], -1)
            if len(self._staged) >= 16:
                self._staged.pop(next(iter(self._staged)))
            self._staged[key] = np.ascontiguousarray(inputs)
        return self._staged[key]

    def _at_samples(self) -> np.ndarray:
        """The model's inputs at the output samples (carriage positions, floor motion)."""
        if self._sample_inputs is None:
            t = self.grid.samples
            self._sample_inputs = inputs_at(self.scenario, t, t)
        return self._sample_inputs

    # -- runs --------------------------------------------------------------------
    def run(
        self,
        changes: Mapping[str, float] | None = None,
        p: np.ndarray | None = None,
        forces: ForceHistory | None = None,
        feedback: FeedbackLaw | None = None,
    ) -> Response:
        """Simulate once.

        Parameters
        ----------
        changes : mapping, optional
            Parameter values by name, e.g. ``{"isolators[0].stiffness.z": 6e5}``.
        p : ndarray, optional
            A whole parameter vector (overrides ``changes``).
        forces : ForceHistory, optional
            Commanded actuator forces (clipped at ``max_force`` and lagged by
            each actuator's bandwidth, see :mod:`isolator.simulation.actuation`).
        feedback : FeedbackLaw, optional
            A sampled controller: its command, held between ticks, is added to
            ``forces`` before saturation and lag.

        Returns
        -------
        Response

        Raises
        ------
        UnstableTableError
            The table has no stable equilibrium.
        SimulationError
            The run diverged.

        Notes
        -----
        Plain carriage transients are integrated with DOP853 steps between the
        breakpoints and read at the samples from its dense output (see
        :mod:`isolator.numerics.dop853`); runs with actuator forces or feedback step
        RK4 on the sample grid, the controller ticking between intervals.
        """
        p = self.parameter_vector(changes) if p is None else np.asarray(p, dtype=float)
        start, end = self.equilibria(p)
        method = self.method_for(max(start.max_frequency, end.max_frequency if end else 0.0))
        return self._run(p, start, end, method, forces, feedback)

    def _with_forces(self, inputs: np.ndarray, substeps: int, forces: ForceHistory | None) -> np.ndarray:
        """The inputs with the actuators' applied forces at every stage time."""
        if forces is None:
            return inputs
        names = tuple(a.name for a in self.scenario.actuators)
        if forces.names != names:
            raise ScenarioError(f"forces: are for actuators {forces.names}, the scenario has {names}")
        times, mid = stage_times(self.grid, substeps)
        flat = times.ravel()
        applied = applied_forces(self.scenario, forces.command(flat, mid.ravel()), flat)
        out = inputs.copy()
        out[..., self.layout.actuator_slice] = applied.reshape(*times.shape, len(names))
        return out

    def _run(
        self,
        p: np.ndarray,
        start: Equilibrium,
        end: Equilibrium | None,
        method: Method,
        forces: ForceHistory | None = None,
        feedback: FeedbackLaw | None = None,
    ) -> Response:
        grid = self.grid
        n = len(self.scenario.carriages)
        if forces is None and feedback is None and method.plan is not None:
            plan = method.plan
            raw, step_peaks, polynomials = _dense_stepper(self.model).run_slots(
                start.state, plan, self._plan_inputs(method, p), p, start.state, with_states=True
            )
            peaks = np.max(step_peaks, axis=0)
            if not np.all(np.isfinite(polynomials)):
                step = int(np.argmax(~np.all(np.isfinite(polynomials), axis=(1, 2))))
                raise SimulationError(f"the run diverged: non-finite state at t = {plan.start[step]:.4g} s")
            signals = _with_start(raw[plan.sample_slots])
            x0 = start.state

            def states() -> np.ndarray:
                return np.vstack([x0, DenseStepper.states(plan, polynomials)])

            at_samples = self._at_samples()
        else:
            substeps = method.substeps
            if feedback is None:
                inputs = self._with_forces(self._model_inputs(substeps), substeps, forces)
                states = _stepper(self.model, substeps).run(start.state, inputs, np.diff(grid.nodes), p)
            else:
                states, inputs = self._run_feedback(p, start, substeps, forces, feedback)
            states = np.vstack([start.state, states])[grid.is_sample]
            at_samples = np.vstack([inputs[:, 0, :], inputs[-1:, -1, :]])[grid.is_sample]
            bad = ~np.all(np.isfinite(states), axis=1)
            if bad.any():
                raise SimulationError(f"the run diverged: non-finite state at t = {grid.samples[np.argmax(bad)]:.4g} s")
            signals = self.signals(states, start)
            peaks = None
        t = grid.samples
        final = None if end is None else self.signals(end.state[None, :], start)[:, 0]
        if final is not None and feedback is not None:
            final = np.asarray(feedback.final(final), dtype=float)
        metrics = self._metrics(signals, final, end, peaks)
        return Response(
            name=self.scenario.name,
            model=self.model.kind,
            t=t,
            signals=signals,
            carriage_names=tuple(c.name for c in self.scenario.carriages),
            q=at_samples[:, :n].T,
            stop_time=self.stop_time,
            final=final,
            settling=metrics,
            state_history=states,
            actuator_names=tuple(a.name for a in self.scenario.actuators),
            actuator_forces=at_samples[:, self.layout.actuator_slice].T,
        )

    def _metrics(
        self,
        signals: np.ndarray,
        final: np.ndarray | None,
        end: Equilibrium | None,
        peaks: np.ndarray | None = None,
        first: int = 0,
    ) -> dict[str, SettlingResult]:
        """Settling of the six signals (6, samples from sample ``first`` on) of a run without NaN;
        ``peaks`` over the whole run when the samples are not all there."""
        t = self.grid.samples[first:]
        peaks = signal_peaks(signals) if peaks is None else peaks
        _check_turn(peaks, t, signals)
        return settling_metrics(t, signals, final, self.stop_time, self.scenario.settling, _hold(end), peaks)

    def _controller_period(self, feedback: FeedbackLaw) -> int:
        """Output samples per controller tick."""
        ratio = self.scenario.simulation.sample_rate / float(feedback.sample_rate)
        period = round(ratio)
        if not (math.isfinite(ratio) and period >= 1 and abs(ratio - period) <= 1e-9 * ratio):
            raise ScenarioError(
                f"simulation.sample_rate: the controller's {feedback.sample_rate:.6g} Hz must divide it "
                f"({self.scenario.simulation.sample_rate:.6g} Hz)"
            )
        return period

    def _run_feedback(
        self, p: np.ndarray, start: Equilibrium, substeps: int, forces: ForceHistory | None,
        feedback: FeedbackLaw,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Step interval by interval, the controller ticking at its rate; the states after each
        interval and the inputs (with the applied forces) at every stage."""
        period = self._controller_period(feedback)
        grid = self.grid
        inputs = self._model_inputs(substeps).copy()  # the actuator forces are filled in as the run goes
        acts = self.layout.actuator_slice
        times, mid = stage_times(grid, substeps)
        # the feedforward command before saturation and lag
        commanded = None if forces is None else forces.command(times.ravel(), mid.ravel()).reshape(*times.shape, -1)
        sample_index = np.cumsum(grid.is_sample) - 1
        ticks = grid.is_sample & (sample_index % period == 0)
        stepper = _stepper(self.model, substeps)
        steps = np.diff(grid.nodes)
        n_a = self.layout.n_actuators
        u = np.zeros(n_a)
        lag = np.zeros(n_a)
        x = start.state.copy()
        out = np.empty((steps.size, x.size))
        feedback.reset()
        motion = np.zeros(12)
        limits = np.array([a.max_force for a in self.scenario.actuators])
        lagged = any(a.bandwidth is not None for a in self.scenario.actuators)
        for i, h in enumerate(steps):
            if ticks[i]:
                u = np.asarray(feedback(float(grid.nodes[i]), motion), dtype=float).reshape(n_a)
            command = u if commanded is None else commanded[i] + u
            if lagged:
                applied = applied_forces(self.scenario, np.broadcast_to(command, (times.shape[1], n_a)), times[i], lag)
                lag = applied[-1]
            else:  # what applied_forces does without a lag, without its per-call overhead
                applied = np.clip(command, -limits, limits)
            inputs[i, :, acts] = applied
            x, motion = stepper.step(x, inputs[i], float(h), p, start.state)
            out[i] = x
            if not np.all(np.isfinite(x)):
                out[i:] = np.nan
                break
        return out, inputs

    def signals(self, states: np.ndarray, start: Equilibrium | np.ndarray) -> np.ndarray:
        """The six table signals (6, N) of model states (N, n_states), relative to ``start``
        (an equilibrium, or reference states, one per row)."""
        reference = start.state if isinstance(start, Equilibrium) else np.asarray(start, dtype=float)
        return self.model.variant.signals(states, reference)

    def run_batch(
        self,
        stiffness: Sequence[float],
        damping: Sequence[float],
        workers: int = 2,
        progress: bool = False,
        diverged: Literal["raise", "record"] = "raise",
    ) -> BatchResult:
        """Many runs with isolator stiffness and damping scaled per run (:func:`~isolator.simulation.batch.run_batch`).

        Parameters
        ----------
        stiffness, damping : sequence of float
            Scale factors on every isolator's stiffness and damping, one per run.
        workers : int
            Threads (the compiled stepping releases the GIL).
        progress : bool
            Print a progress line every 10 %.
        diverged : {"raise", "record"}
            Stop at a diverging run, or give it NaN metrics and its reason in ``failures``.
        """
        from isolator.simulation.batch import run_batch

        return run_batch(self, stiffness, damping, workers, progress, diverged)

    def scaled_parameter_sets(
        self, stiffness: float | Sequence[float], damping: float | Sequence[float]
    ) -> np.ndarray:
        """Parameter vectors (runs, parameters) with all isolator stiffness and damping scaled per run.

        A bad scale is named by its index (``stiffness[3]: ...``) when the scales are sequences.
        """
        k = _scales(stiffness, "stiffness", positive=True)
        c = _scales(damping, "damping", positive=False)
        if k.size != c.size:
            raise ScenarioError("damping: needs one scale per stiffness scale")
        names = self.layout.names
        stiff = np.array([".stiffness." in n for n in names])
        damp = np.array([".damping." in n for n in names])
        scale = np.where(stiff, k[:, None], np.where(damp, c[:, None], 1.0))
        return self.parameters[None, :] * scale


def _scales(values: float | Sequence[float], key: str, positive: bool) -> np.ndarray:
    """Scale factors as an array, each finite and > 0 (``positive``) or >= 0; one clear error naming ``key``."""
    array = np.asarray(values, dtype=float)
    flat = array.reshape(-1)
    bad = ~(np.isfinite(flat) & ((flat > 0) if positive else (flat >= 0)))
    if bad.any():
        i = int(np.argmax(bad))
        where = key if array.ndim == 0 else f"{key}[{i}]"
        raise ScenarioError(f"{where}: scale must be a finite number {'>' if positive else '>='} 0, got {flat[i]}")
    return flat


def _check_turn(peaks: np.ndarray, t: np.ndarray | None = None, signals: np.ndarray | None = None) -> None:
    """Report a run whose rotation peaks pass ``MAX_TURN`` as diverged (naming the first sample past it
    when the signals (6, samples) at times ``t`` are given)."""
    if np.max(peaks[3:]) <= MAX_TURN:
        return
    when = ""
    if signals is not None and t is not None:
        too_far = np.max(np.abs(signals[3:]), axis=0) > MAX_TURN
        when = f" at t = {t[np.argmax(too_far)]:.4g} s" if too_far.any() else ""
    raise SimulationError(f"the run diverged: the table turned by more than {MAX_TURN:g} rad{when}")


def _with_start(signals: np.ndarray) -> np.ndarray:
    """Signals (samples - 1, 6) after the start as (6, samples) rows, C order, zero at the start."""
    out = np.zeros((6, signals.shape[0] + 1))
    out[:, 1:] = signals.T
    return out


def _hold(end: Equilibrium | None) -> float:
    """How long [s] a signal must be seen settled before the run ends: the period of the slowest
    oscillating mode at the final equilibrium (0 if none, or no final equilibrium)."""
    if end is None:
        return 0.0
    im = np.abs(np.imag(end.eigenvalues))
    im = im[im > 1e-6]
    return float(2 * math.pi / im.min()) if im.size else 0.0


def simulate(scenario: Scenario, model: str = "exact", changes: Mapping[str, float] | None = None) -> Response:
    """Simulate a scenario's carriage transients from the initial static equilibrium.

    Parameters
    ----------
    scenario : Scenario
    model : {"exact", "paper"}
    changes : mapping, optional
        Parameter values by name (see :attr:`ParameterLayout.names`).

    Returns
    -------
    Response
    """
    return Simulator(scenario, model).run(changes)
