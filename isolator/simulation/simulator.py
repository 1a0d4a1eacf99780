"""Transient simulation of a scenario: from the initial equilibrium through the moves. Plain carriage transients
are integrated with DOP853 steps between the breakpoints and read at the samples from its dense output
(:mod:`isolator.numerics.dop853`); runs with actuator forces or a controller step RK4 on the sample grid, a
controller ticking in the compiled loop (:mod:`isolator.simulation.closed_loop`)."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from functools import cache, cached_property
from typing import Literal

import numpy as np

from isolator.errors import SimulationError, UnstableTableError
from isolator.model.cache import get_model
from isolator.model.equilibrium import Equilibrium, air_in_groups, static_equilibria
from isolator.model.names import expand_changes
from isolator.model.parameters import ParameterLayout
from isolator.model.tipping import rocking_over, tipping_verdict, travel_configurations
from isolator.numerics.dop853 import DenseStepper, StepPlan
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import SIGNALS, Scenario
from isolator.scenario.validation import check_motion
from isolator.simulation.actuation import ForceHistory, with_forces
from isolator.simulation.batch import BatchResult, run_batch, scale_label
from isolator.simulation.batch_setup import both_rests
from isolator.simulation.closed_loop import FeedbackLaw, LoopGrids, closed_loop_run
from isolator.simulation.dense_metrics import DenseRuns, run_metrics
from isolator.simulation.discrete_controller import DiscreteController
from isolator.simulation.elastic_method import QuasiStaticRun, check_elastic
from isolator.simulation.leveling import PneumaticResult, metric_grid, pneumatic_result
from isolator.simulation.method_choice import MethodChoice
from isolator.simulation.resources import check_run_memory
from isolator.simulation.response import Response
from isolator.simulation.scaling import scaled_parameter_sets
from isolator.simulation.sensors import sensor_history
from isolator.simulation.settling import Band, SettlingResult, settling_metrics, signal_peaks
from isolator.simulation.stepping import (
    Method,
    check_turn,
    dense_stepper,
    hold_time,
    keep_newest,
    plan_stage_inputs,
    rk4_stepper,
)
from isolator.simulation.tail_check import KnownRests, run_tail
from isolator.simulation.time_grid import TimeGrid, grid_breakpoints, inputs_at, model_inputs, time_grid
from isolator.simulation.valve_events import dense_run
from isolator.simulation.window_random import with_random_margins
from isolator.simulation.window_settling import run_points

__all__ = ["FeedbackLaw", "Method", "Simulator", "get_model"]


class Simulator(MethodChoice):
    """A scenario's model built once, run many times.

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).
    model : {"exact", "paper"}
        The exact rigid-body model, or the paper's small-angle model.
    elastic : {"auto", "dynamic", "quasi-static"}
        A bending top's modes in a transient (:mod:`isolator.simulation.elastic_method`).

    Examples
    --------
    >>> from isolator import load_scenario, Simulator
    >>> sim = Simulator(load_scenario("paper-table-3-2"))
    >>> response = sim.run()
    >>> response.settling_time_max  # doctest: +SKIP
    """

    def __init__(self, scenario: Scenario, model: str = "exact", elastic: str = "auto") -> None:
        self.elastic = check_elastic(elastic)
        check_motion(scenario)
        check_run_memory(scenario)  # a grid the machine cannot hold: one clear error, not numpy's
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
        self._loops: LoopGrids = {}  # the closed loops' grids and inputs
        self._plans: dict[int, StepPlan] = {}
        self._staged: dict[tuple[int, bytes], np.ndarray] = {}
        self._quasi_values: dict[tuple[int, bytes], np.ndarray] = {}  # a quasi-static top's stage values
        self._quasi_rests: dict[bytes, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}  # and its rests
        self._sample_inputs: np.ndarray | None = None
        self._tipping: dict[bytes, str] = {}
        self._rests: dict[bytes, KnownRests] = {}  # the newest parameter vectors' rests, for runs of the same table

    # -- parameters ------------------------------------------------------------
    def parameter_vector(self, changes: Mapping[str, float] | None = None) -> np.ndarray:
        """The parameter vector with named entries changed (names: ``layout.names``, or as ``isolator.sweep``
        takes them: ``isolators[*].damping.z``, ``isolators[0].stiffness``), each checked by the rules the file
        reader checks by (:mod:`isolator.scenario.rules`).

        Raises
        ------
        ParameterError
            Naming the entry, ``changes['isolators[0].damping.z']: must be >= 0, got -5``; an unknown
            name with the closest valid one.
        """
        return self.layout.with_changes(self.parameters, expand_changes(self.layout, changes))  # type: ignore[arg-type]

    def scaled_parameters(self, stiffness: float = 1.0, damping: float = 1.0) -> np.ndarray:
        """Parameter vector with all isolator stiffness and damping scaled (:func:`scaled_parameter_sets`)."""
        return self.scaled_parameter_sets(stiffness, damping)[0]

    def scaled_parameter_sets(
        self, stiffness: float | Sequence[float] | np.ndarray, damping: float | Sequence[float] | np.ndarray
    ) -> np.ndarray:
        """Parameter vectors (runs, parameters) with every isolator's stiffness and damping scaled per run
        (:func:`~isolator.simulation.scaling.scaled_parameter_sets`, pneumatic isolators included)."""
        return scaled_parameter_sets(self.layout, self.parameters, stiffness, damping)

    # -- pieces ----------------------------------------------------------------
    @cached_property
    def default_band(self) -> Band:
        """The scenario's ``[settling]`` rule as a band (:meth:`Band.from_settling`), what a run measures by default."""
        return Band.from_settling(self.scenario.settling)

    def equilibria(self, p: np.ndarray) -> tuple[Equilibrium, Equilibrium | None]:
        """Initial and final static equilibria (final None if a carriage never stops); those of the newest
        parameter vectors are kept (read-only), for the runs of the same table."""
        known = self.known_rests(p)
        return known.start, known.end

    def known_rests(self, p: np.ndarray) -> KnownRests:
        """The rests of :meth:`equilibria` with what runs of that table share (kept for the newest 16 vectors)."""
        p = np.asarray(p, dtype=float)
        key = p.tobytes()
        known = self._rests.get(key)
        if known is None:
            start, end = self.equilibria_of(p[None, :])
            known = self._rests[key] = KnownRests(self.model, p.copy(), start[0], end[0])
            keep_newest(self._rests, None)
        return known

    def equilibria_of(self, params: np.ndarray) -> tuple[list[Equilibrium], list[Equilibrium | None]]:
        first, last = self._positions
        both = None if last is None or self.layout.pneumatic else both_rests(self.model, params, first, last)
        if both is not None:  # both rests in one solve
            return both
        start = static_equilibria(self.model, params, first, "with the carriages at their start")
        if last is None:
            return start, [None] * len(start)
        # pneumatic: groups without a valve keep the air they start with (docs/scenario-format.md)
        air = None if self.layout.pneumatic is None else air_in_groups(
            self.model, np.array([e.state for e in start]), params
        )
        where = "with the carriages at their final positions"
        return start, list(static_equilibria(self.model, params, last, where, air=air))

    def check_tipping(self, p: np.ndarray) -> None:
        """Refuse what ``isolator stability`` calls unstable, in its words (:mod:`isolator.model.tipping`)."""
        key = np.asarray(p, dtype=float).tobytes()
        if key not in self._tipping:
            configs = travel_configurations(self.scenario)
            stable, _, line = tipping_verdict(configs, rocking_over(get_model(self.layout, "exact"), p, configs))
            self._tipping[key] = "" if stable else line
            keep_newest(self._tipping, None, 64)
        if self._tipping[key]:
            raise UnstableTableError(self._tipping[key])

    def grid_inputs(self, substeps: int) -> np.ndarray:
        """The model's inputs at every RK4 stage of the grid, ``substeps`` steps per interval (cached)."""
        if substeps not in self._inputs:
            self._inputs[substeps] = model_inputs(self.scenario, self.grid, substeps)
        return self._inputs[substeps]

    def plan_inputs(self, method: Method, p: np.ndarray) -> np.ndarray:
        """The DOP853 stepper's inputs at every stage of the plan: the model's inputs, or their
        staged form (time-only moments; cached per carriage and table inertia, :func:`plan_stage_inputs`)."""
        return plan_stage_inputs(self.scenario, self.model, method, p, self._staged)

    def _at_samples(self) -> np.ndarray:
        """The model's inputs at the output samples (carriage positions, floor motion)."""
        if self._sample_inputs is None:
            self._sample_inputs = inputs_at(self.scenario, self.grid.samples, self.grid.samples)
        return self._sample_inputs

    # -- runs --------------------------------------------------------------------
    def run(
        self,
        changes: Mapping[str, float] | None = None,
        p: np.ndarray | None = None,
        forces: ForceHistory | None = None,
        feedback: FeedbackLaw | None = None,
        band: Band | None = None,
        controller: DiscreteController | None = None,
        noise: bool = False,
        seed: int = 0,
    ) -> Response:
        """Simulate once.

        Parameters
        ----------
        changes : mapping, optional
            Parameter values by name, e.g. ``{"isolators[0].stiffness.z": 6e5}`` (``isolators[*].damping`` too).
        p : ndarray, optional
            A whole parameter vector (overrides ``changes``).
        forces : ForceHistory, optional
            Commanded actuator forces (clipped at ``max_force`` and lagged by
            each actuator's bandwidth, see :mod:`isolator.simulation.actuation`).
        feedback : FeedbackLaw, optional
            A sampled state-feedback law: its command, held between ticks, is added to
            ``forces`` before saturation and lag.
        band : Band, optional
            The settling band (default: the scenario's ``[settling]`` rule, :meth:`Band.from_settling`);
            ``Response.with_band`` measures the same run in another.
        controller : DiscreteController, optional
            A controller of the scenario's sensors (``controller.json``), run as ``docs/scenario-format.md``
            says (:mod:`isolator.simulation.closed_loop`); not with ``feedback``.
        noise : bool
            Add each sensor's noise to the controller's readings [SI]: white of its ``noise`` RMS per sample,
            or with the one-sided PSD ``noise_psd`` below half the controller's rate.
        seed : int
            Seed of that noise.

        Returns
        -------
        Response

        Raises
        ------
        UnstableTableError
            The table has no stable equilibrium.
        SimulationError
            The run diverged.
        """
        p = self.parameter_vector(changes) if p is None else self.layout.checked(p, "p")
        self.check_tipping(p)
        start, end = self.equilibria(p)
        actuated = forces is not None or feedback is not None or controller is not None
        return self.run_method(p, start, end, self.method_of(start, end, actuated), forces, feedback, band, controller,
                               noise, seed)

    def run_method(
        self,
        p: np.ndarray,
        start: Equilibrium,
        end: Equilibrium | None,
        method: Method,
        forces: ForceHistory | None = None,
        feedback: FeedbackLaw | None = None,
        band: Band | None = None,
        controller: DiscreteController | None = None,
        noise: bool = False,
        seed: int = 0,
    ) -> Response:
        """One run from the equilibria ``start`` (and ``end``, None if a carriage never stops) with
        ``method`` (as :meth:`method_for` gives it); the rest as :meth:`run`."""
        grid = self.grid
        windowed = with_random_margins(self.scenario, p, controller)  # before the run: a filled window is refused
        final = None if end is None else dense_stepper(self.model).signal_values(end.state, start.state)
        if final is not None and feedback is not None:
            final = np.asarray(feedback.final(final), dtype=float)
        hold = hold_time(end)
        if forces is None and feedback is None and controller is None and method.plan is not None:
            quasi = (QuasiStaticRun(self, p, start, self._quasi_values, self._quasi_rests) if method.quasi_static
                     else None)
            stepping, first = (self, start) if quasi is None else (quasi, quasi.start)
            plan, (raw, step_peaks, deviations, polynomials, signals) = dense_run(stepping, method, p, first, final)
            end_time = np.array([plan.end])
            last = DenseStepper.states_at(plan, polynomials, end_time)
            if not np.all(np.isfinite(polynomials)):  # all of it: the dense-only stages reach no step's start
                step = int(np.argmax(~np.all(np.isfinite(polynomials), axis=(1, 2))))
                raise SimulationError(f"the run diverged: non-finite state at t = {plan.start[step]:.4g} s")
            runs = DenseRuns.of_run(plan, (raw, step_peaks, deviations, polynomials), first.state, stepping.model)
            x0, dense = start.state, polynomials
            expand = (lambda _, x: x) if quasi is None else quasi.expand  # the full model's states
            known = self._rests.get(p.tobytes())
            modes = known.modes if known is not None and known.start is start and known.end is end else None
            free = run_tail(self.scenario, self.model, p, start, end, expand(end_time, last)[0], plan.end, modes)

            def measure(rule: Band) -> dict[str, SettlingResult]:
                return run_metrics(runs, final, self.stop_time, rule, hold, self.grid.samples, signals, *free)

            @cache  # the states at the samples, once for the response, leveling and windows
            def history() -> np.ndarray:
                return np.vstack([x0, expand(grid.samples[1:], DenseStepper.states(plan, dense))])

            @cache  # leveling and windows, read at >= 1 kHz (the samples themselves when as dense)
            def fine() -> tuple[np.ndarray, np.ndarray]:
                times = metric_grid(grid.samples, float(grid.nodes[-1]))
                return times, history() if times is grid.samples else np.vstack(
                    [x0, expand(times[1:], DenseStepper.states_at(plan, dense, times[1:]))])

            states: np.ndarray | None = None
            at_samples = self._at_samples()
        else:
            substeps = method.substeps
            if feedback is None and controller is None:
                taken, inputs = with_forces(self.scenario, self.layout.actuator_slice, self.grid,
                                            self.grid_inputs(substeps), substeps, forces)
                stepped = rk4_stepper(self.model, substeps, taken.shape[1] != inputs.shape[1]).run(
                    start.state, taken, np.diff(grid.nodes), p)
            else:
                grid, stepped, inputs = closed_loop_run(
                    self.scenario, self.model, (self.grid, self.grid_inputs, self.substeps_for, self._loops), p,
                    (start, end), substeps, forces, feedback, controller, noise, seed)
            every = np.vstack([start.state, stepped])
            at_samples = np.vstack([inputs[:, 0, :], inputs[-1:, -1, :]])[grid.is_sample]
            bad = ~np.all(np.isfinite(every), axis=1)
            if bad.any():
                raise SimulationError(f"the run diverged: non-finite state at t = {grid.nodes[np.argmax(bad)]:.4g} s")
            states = every[grid.is_sample]
            fine = cache(lambda: (grid.nodes, every))  # the internal grid, >= 1 kHz (typed as in the other branch)
            on_grid = self.signals(every, start)  # the metrics are taken on the whole internal grid
            signals = np.ascontiguousarray(on_grid[:, grid.is_sample])
            # forces or feedback act to the end: no free motion after it, the run must show the signal settled
            free = (None, "") if forces is not None or feedback is not None or controller is not None else run_tail(
                self.scenario, self.model, p, start, end, every[-1], float(grid.nodes[-1]))

            peaks = signal_peaks(on_grid)  # the metrics on every node, the entry into a band interpolated
            check_turn(peaks, grid.nodes, on_grid)

            def measure(rule: Band) -> dict[str, SettlingResult]:
                return settling_metrics(grid.nodes, on_grid, final, self.stop_time, rule, hold, peaks, True, *free)

        t = grid.samples
        run_states = history if states is None else (lambda: states)

        def remeasure(rule: Band) -> tuple[dict[str, SettlingResult], Band, Callable[[], PneumaticResult] | None]:
            metrics = measure(rule)
            peaks_all = np.array([metrics[k].peak for k in SIGNALS])
            resolved = rule.resolved(peaks_all)
            if not self.scenario.is_pneumatic:
                return metrics, resolved, None
            return metrics, resolved, lambda: pneumatic_result(self.scenario, self.model, p, t, run_states(), signals,
                                                               start, peaks_all, hold, resolved, fine())

        metrics, resolved, pneumatic = remeasure(self.default_band if band is None else band)
        points, windows = run_points(windowed, self.model.kind, start.state, None if end is None else end.state,
                                     self.stop_time, hold, fine, free)

        return Response(
            name=self.scenario.name,
            model=self.model.kind,
            t=t,
            signals=signals,
            carriage_names=tuple(c.name for c in self.scenario.carriages),
            q=at_samples[:, : len(self.scenario.carriages)].T,
            stop_time=self.stop_time,
            final=final,
            settling=metrics,
            band=resolved,
            remeasure=remeasure,
            state_history=history if states is None else states,
            actuator_names=tuple(a.name for a in self.scenario.actuators),
            actuator_forces=at_samples[:, self.layout.actuator_slice].T,
            pneumatic_result=pneumatic,
            point_set=points,
            window_result=windows,
            sensor_set=self.scenario.sensors,
            sensor_history=sensor_history(self.scenario, self.model, t, run_states, at_samples, p, start.state),
            deadbands={g.name: g.valve.deadband for g in self.scenario.leveling if g.valve is not None},
            move_start=min((b for c in self.scenario.carriages for b in c.profile.breakpoints[:1]), default=0.0),
        )

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
        band: Band | None = None,
    ) -> BatchResult:
        """Runs with every isolator's stiffness and damping scaled per run (:meth:`scaled_parameter_sets`); the rest
        as for :func:`~isolator.simulation.batch.run_batch` (:func:`isolator.sweep.sweep` varies any parameter)."""
        return run_batch(self, self.scaled_parameter_sets(stiffness, damping), workers, progress, diverged, band,
                         scale_label(stiffness, damping))


check_public(globals(), ("Simulator",))
