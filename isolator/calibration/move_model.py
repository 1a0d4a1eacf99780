"""The full time-varying model's sensor signals for a move experiment, many parameter vectors at once.

The scenario runs from its initial equilibrium to the record's last time, sampled at the record's rate
(``t = 0`` of the scenario is ``t = 0`` of the record). The runs of one call (a fit's point and its
perturbations) share one DOP853 step plan, the finest any of them needs, so that their differences are
smooth in the parameters, and are stepped side by side in the compiled loop's SIMD lanes
(:func:`isolator.simulation.stepping.dense_stepper`), four at a time, on two threads; their states at the
samples come from the steps' dense output and become sensor signals
(:func:`isolator.simulation.sensors.sensor_signals`).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np

from isolator.errors import ScenarioError, SimulationError
from isolator.numerics.dop853 import DenseStepper
from isolator.scenario.definitions import Scenario, SimulationSettings
from isolator.scenario.sensors import Sensor
from isolator.simulation.batch import LANES
from isolator.simulation.resources import check_run_memory
from isolator.simulation.sensors import sensor_signals
from isolator.simulation.simulator import Simulator
from isolator.simulation.stepping import Method, dense_stepper, staged_parameters
from isolator.simulation.time_grid import inputs_at, internal_rate

__all__ = ["MoveModel"]


class MoveModel:
    """Sensor signals of a scenario's move at a record's sample times.

    Parameters
    ----------
    scenario : Scenario
    t : ndarray (N,)
        The record's sample times [s], uniformly spaced, from ``t[0] >= 0``.
    sensors : tuple of Sensor
        The table sensors to give, in order.
    key : str
        How errors name the experiment.
    """

    def __init__(self, scenario: Scenario, t: np.ndarray, sensors: tuple[Sensor, ...], key: str) -> None:
        t = np.asarray(t, dtype=float)
        if scenario.sequence is not None:
            raise ScenarioError(f"{key}: a move experiment runs the scenario's own move, not a [sequence]")
        if not scenario.carriages or scenario.stop_time == 0.0:
            raise ScenarioError(f"{key}: kind = \"move\" needs carriages that move (the scenario's profiles)")
        if t[-1] <= scenario.stop_time:
            raise ScenarioError(f"{key}: the record ends at t = {t[-1]:.6g} s, before the carriages stop at "
                                f"{scenario.stop_time:.6g} s (a move experiment records the whole move)")
        rate = (t.size - 1) / (t[-1] - t[0])
        first = t[0] * rate
        if t[0] < 0 or abs(first - round(first)) > 1e-6 * max(1.0, first):
            raise ScenarioError(f"{key}: the record must start at t >= 0 on its own sample grid (t = 0 is the "
                                f"scenario's start), got t = {t[0]:.9g} s with spacing {1 / rate:.9g} s")
        self.first = round(first)
        self.count = t.size
        settings = SimulationSettings(duration=(self.first + t.size - 1) / rate, sample_rate=rate)
        self.scenario = replace(scenario, simulation=settings, ground=None)  # the floor is still (the contract)
        check_run_memory(self.scenario, f"{key}: the record's {settings.duration:g} s, simulated at "
                                        f"{internal_rate(settings)[0]:g} Hz,")
        self.sensors = sensors
        self.sim = Simulator(self.scenario)
        samples = self.sim.grid.samples
        if samples.size != self.first + t.size:
            raise ScenarioError(f"{key}: the record's samples do not fall on a uniform grid from t = 0")
        self.t = samples[self.first :]
        self._inputs = inputs_at(self.scenario, samples, samples)

    def signals(self, params: np.ndarray, workers: int = 2) -> np.ndarray:
        """Sensor signals (runs, sensors, N) [SI] of the runs with parameter vectors ``params`` (runs, size).

        Raises
        ------
        UnstableTableError
            A run's table has no stable rest.
        SimulationError
            A run diverged.
        """
        sim = self.sim
        params = np.atleast_2d(np.asarray(params, dtype=float))
        starts, ends = sim.equilibria_of(params)
        methods = [sim.method_for(max(s.max_frequency, e.max_frequency if e is not None else 0.0))
                   for s, e in zip(starts, ends, strict=True)]
        out = np.empty((params.shape[0], len(self.sensors), self.count))
        if any(m.plan is None for m in methods):  # RK4 on the sample grid: one by one, the finest substeps
            method = Method(max(m.substeps for m in methods))
            for i in range(params.shape[0]):
                run = sim.run_method(params[i], starts[i], ends[i], method)
                out[i] = self._read(run.states, params[i], starts[i].state)
            return out
        method = max(methods, key=lambda m: m.plan_key)
        uses = staged_parameters(sim.model)
        groups: dict[bytes, list[int]] = {}
        for i in range(params.shape[0]):
            groups.setdefault(params[i, uses].tobytes(), []).append(i)
        packs = [(rows[lo : lo + LANES], rows[0]) for rows in groups.values() for lo in range(0, len(rows), LANES)]
        inputs = {first: sim.plan_inputs(method, params[first]) for _, first in packs}
        stepper = dense_stepper(sim.model, LANES)
        plan = method.plan
        assert plan is not None

        states: dict[int, np.ndarray] = {}

        def pack(runs: list[int], first: int) -> None:
            """Step ``runs`` side by side (the compiled loop releases the GIL); their states at the samples."""
            lanes = runs + runs[-1:] * (LANES - len(runs))
            x0 = np.array([starts[i].state for i in lanes])
            _, _, _, polys = stepper.run_slots(x0, plan, inputs[first], params[lanes], x0, with_states=True)
            assert polys is not None
            for lane, i in enumerate(runs):
                states[i] = np.vstack([x0[lane], DenseStepper.states(plan, polys[..., lane])])

        if workers <= 1 or len(packs) == 1:
            for runs, first in packs:
                pack(runs, first)
        else:
            with ThreadPoolExecutor(max_workers=workers) as pool:
                list(pool.map(lambda job: pack(*job), packs))
        for i in range(params.shape[0]):  # casadi's evaluations in this thread only
            if not np.all(np.isfinite(states[i])):
                bad = int(np.argmax(~np.all(np.isfinite(states[i]), axis=1)))
                raise SimulationError(f"the run diverged: non-finite state at t = {sim.grid.samples[bad]:.4g} s")
            out[i] = self._read(states[i], params[i], starts[i].state)
        return out

    def _read(self, states: np.ndarray, p: np.ndarray, start: np.ndarray) -> np.ndarray:
        """The sensors' signals at the record's samples from the states at every sample from t = 0."""
        s = slice(self.first, None)
        return sensor_signals(self.scenario, self.sim.model, self.sim.grid.samples[s], states[s], self._inputs[s], p,
                              start, self.sensors)
