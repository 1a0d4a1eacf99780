"""How a run is integrated, shared by single runs and batches: the steppers (built once per model),
the choice between DOP853 steps and RK4 on the sample grid, and the checks every run passes."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from isolator.errors import ScenarioError, SimulationError
from isolator.model.equilibrium import Equilibrium
from isolator.model.parameters import ParameterLayout
from isolator.model.quasi_static_top import QuasiStaticTop
from isolator.model.signals import signal_function
from isolator.model.variants import Model
from isolator.numerics.dop853 import DenseStepper, StepPlan
from isolator.numerics.dop853_driver import signal_rows
from isolator.numerics.native import MappedFunction
from isolator.numerics.rk4 import Stepper
from isolator.numerics.systems import Unstaged
from isolator.scenario.definitions import Isolator, Scenario
from isolator.scenario.profiles import SineProfile
from isolator.simulation.time_grid import inputs_at

__all__ = [
    "DENSE_STEP_ANGLE",
    "LEVER_LIMIT",
    "MAX_DENSE_STEP",
    "MAX_STEPS",
    "MAX_TURN",
    "STEP_ANGLE",
    "Method",
    "check_step_count",
    "check_turn",
    "clear_caches",
    "dense_stepper",
    "fastest_input",
    "fastest_rate",
    "hold_time",
    "keep_newest",
    "plan_stage_inputs",
    "rk4_stepper",
    "signal_width",
    "stage_inputs",
    "staged_map",
    "staged_parameters",
]

#: most the table may turn [rad] before a run is reported as diverged
MAX_TURN = 0.2
#: largest |lambda| h per RK4 step; keeps the relative error well below 1e-6
STEP_ANGLE = 0.05
#: largest |lambda| h per DOP853 step (Table 3.2: 2e-8 relative RMS at 0.9, 1e-7 with stiffness x2)
DENSE_STEP_ANGLE = 0.9
#: longest DOP853 step [s]; shorter ones come in ratios of 2^(1/8)
MAX_DENSE_STEP = 0.05

_STEPPERS: dict[tuple[ParameterLayout, str, int, bool], Stepper] = {}
_DENSE: dict[tuple[ParameterLayout, str, int, bool], DenseStepper] = {}


@dataclass(frozen=True)
class Method:
    """How a run is integrated: DOP853 steps (``plan``) or RK4 on the sample grid (``substeps``); a bending
    top's modes quasi-static (:mod:`isolator.simulation.elastic_method`) when ``quasi_static``."""

    substeps: int
    plan: StepPlan | None = None
    plan_key: int = 0
    quasi_static: bool = False


def rk4_stepper(model: Model, substeps: int, split: bool = False) -> Stepper:
    """The compiled RK4 stepper of a model with ``substeps`` steps per grid interval (built once); ``split``: four
    inputs per step (lagged actuators' forces, :func:`~isolator.simulation.actuation.with_forces`)."""
    key = (model.layout, model.kind, substeps, split)
    if key not in _STEPPERS:
        _STEPPERS[key] = Stepper(model, substeps, model.variant.sensed_motion, split=split)
    return _STEPPERS[key]


def dense_stepper(model: Model | QuasiStaticTop, lanes: int = 1, staged: bool = True) -> DenseStepper:
    """The DOP853 stepper of a model, ``lanes`` runs per call (built once); ``staged`` False: through the
    whole right-hand side (:class:`~isolator.numerics.systems.Unstaged`: inputs shared by runs whose
    time-only part differs)."""
    key = (model.layout, model.kind, lanes, staged)
    if key not in _DENSE:
        system = model if staged or model.staged_rhs is None else Unstaged.of(model)
        _DENSE[key] = DenseStepper(system, signal_function(model.variant, model.n_states), lanes)
    return _DENSE[key]


@lru_cache(maxsize=16)
def signal_width(model: Model | QuasiStaticTop) -> int:
    """How many leading states the table signals read (their dense output is all the metrics need)."""
    return max(signal_rows(signal_function(model.variant, model.n_states), model.n_states)) + 1


@lru_cache(maxsize=16)
def staged_parameters(model: Model) -> np.ndarray:
    """Indices of the parameters the model's staged inputs depend on (none without a staged form)."""
    if model.staged_inputs is None:
        return np.zeros(0, dtype=int)
    c, p = model.staged_inputs.sx_in()
    v = model.staged_inputs(c, p)
    return np.array([i for i in range(p.shape[0]) if ca.depends_on(v, p[i])], dtype=int)


@lru_cache(maxsize=16)
def staged_map(model: Model) -> MappedFunction:
    """The model's staged inputs, compiled for many stage times at once (the model has a staged form)."""
    if model.staged_inputs is None:
        raise ValueError(f"{model.tag}: the model has no staged inputs")
    return MappedFunction(model.staged_inputs, f"isolator_staged_{model.tag}", block=256, optimisation="-O1")


def clear_caches() -> None:
    """Forget the steppers and staged-input functions built so far (for timing a cold start)."""
    _STEPPERS.clear()
    _DENSE.clear()
    staged_map.cache_clear()
    staged_parameters.cache_clear()


def check_turn(peaks: np.ndarray, t: np.ndarray | None = None, signals: np.ndarray | None = None) -> None:
    """Report a run whose rotation peaks pass ``MAX_TURN`` as diverged (naming the first sample past it
    when the signals (6, samples) at times ``t`` are given)."""
    if np.max(peaks[3:]) <= MAX_TURN:
        return
    when = ""
    if signals is not None and t is not None:
        too_far = np.max(np.abs(signals[3:]), axis=0) > MAX_TURN
        when = f" at t = {t[np.argmax(too_far)]:.4g} s" if too_far.any() else ""
    raise SimulationError(f"the run diverged: the table turned by more than {MAX_TURN:g} rad{when}")


def hold_time(end: Equilibrium | None) -> float:
    """How long [s] a signal must be seen settled before the run ends: the period of the slowest
    oscillating mode at the final equilibrium (0 if none, or no final equilibrium)."""
    if end is None:
        return 0.0
    im = np.abs(np.imag(end.eigenvalues))
    im = im[im > 1e-6]
    return float(2 * math.pi / im.min()) if im.size else 0.0


#: the staged inputs a simulator keeps for reuse, at most this many bytes (and 16 plans)
STAGED_BYTES = 512 * 2**20


def plan_stage_inputs(scenario: Scenario, model: Model, method: Method, p: np.ndarray,
                      cache: dict[tuple[int, bytes], np.ndarray]) -> np.ndarray:
    """The DOP853 stepper's inputs at every stage of ``method``'s plan: the model's inputs, or their staged form
    (time-only moments), kept in ``cache`` per plan and the parameters they depend on (carriage and table
    inertia; the oldest dropped past 16 entries or :data:`STAGED_BYTES`)."""
    key = (method.plan_key, np.asarray(p, dtype=float)[staged_parameters(model)].tobytes())
    if key not in cache:
        if method.plan is None:
            raise ValueError("plan_inputs: the method steps RK4 on the sample grid, it has no step plan")
        cache[key] = stage_inputs(scenario, model, method.plan, p)
        keep_newest(cache, STAGED_BYTES)
    return cache[key]


def keep_newest(cache: dict[Any, Any], budget: int | None, most: int = 16) -> None:
    """Drop a cache's oldest entries (insertion order) until at most ``most`` are left and, unless ``budget`` is
    None, their arrays together take at most ``budget`` bytes; the newest is always kept."""
    while len(cache) > 1 and (len(cache) > most or (
            budget is not None and sum(a.nbytes for a in cache.values()) > budget)):
        cache.pop(next(iter(cache)))


def fastest_rate(scenario: Scenario, omega_max: float) -> float:
    """The fastest rate [rad/s] a run's steps must resolve: the equilibria's fastest eigenvalue ``omega_max`` and
    the sine drives (a carriage's or the floor's ``omega``). The actuators' first-order lags are not among them:
    the RK4 steps take a lagged force through :func:`~isolator.simulation.actuation.lag_stages`, which integrates
    it as exactly as the step does the table, however fast the lag (without it, a 200 Hz lag made one RK4 step
    per millisecond stray by 1e-5 of a signal's peak, and resolving the lag's rate took 26 steps)."""
    drives = [c.profile for c in scenario.carriages]
    drives += list(scenario.ground.motion.values()) if scenario.ground is not None else []
    return max([omega_max, *(abs(d.omega) for d in drives if isinstance(d, SineProfile))])


def stage_inputs(scenario: Scenario, model: Model, plan: StepPlan, p: np.ndarray) -> np.ndarray:
    """The DOP853 stepper's inputs at every stage of ``plan``: the model's inputs, or their staged form (time-only
    moments) with the parameters ``p``; :func:`plan_stage_inputs` keeps them per plan."""
    inputs = inputs_at(scenario, *plan.stage_times())
    if model.staged_inputs is not None:
        flat = inputs.reshape(inputs.shape[0] * inputs.shape[1], inputs.shape[2])
        inputs = staged_map(model)(flat, p)[0].reshape(*inputs.shape[:2], -1)
    return np.ascontiguousarray(inputs)


#: the most integration steps one run may take
MAX_STEPS = 2e7


def check_step_count(omega: float, duration: float, angle: float, scenario: Scenario | None = None) -> None:
    """Refuse a run whose fastest eigenvalue ``omega`` [1/s] needs more than :data:`MAX_STEPS` explicit steps
    of ``|lambda| h <= angle`` over ``duration`` [s], naming the scenario's input that most likely makes it when
    ``scenario`` is given: a sine drive (a carriage's or the floor's) at least as fast, else
    :func:`fastest_input`."""
    steps = duration * omega / angle
    if math.isfinite(steps) and steps <= MAX_STEPS:
        return
    drives = [] if scenario is None else [(f"carriages[{i}].profile", c.profile)
                                          for i, c in enumerate(scenario.carriages)]
    if scenario is not None and scenario.ground is not None:
        drives += [(f"ground.{axis}", profile) for axis, profile in scenario.ground.motion.items()]
    sines = [(abs(p.omega), key) for key, p in drives if isinstance(p, SineProfile)]
    fastest = max(sines, default=(0.0, ""))
    if fastest[0] >= omega:
        raise ScenarioError(f"{fastest[1]}.omega: a sine of {fastest[0]:.3g} rad/s needs about {steps:.3g} "
                            f"integration steps for this {duration:g} s run (at most {MAX_STEPS:g}): faster than "
                            "any stage or floor moves")
    cause = fastest_input(scenario, omega) if scenario is not None else None
    key, why = cause or ("isolators", "a stiffness or damping far beyond a real isolator's, or much too light "
                                      "a table")
    raise ScenarioError(
        f"{key}: the table's fastest mode (|lambda| = {omega:.3g} 1/s) needs about {steps:.3g} integration "
        f"steps for this {duration:g} s run (at most {MAX_STEPS:g}): {why}"
    )


#: a lever ``r^2 m / I`` beyond this is not a table's (a uniform box's corner: 3; its isolators in mm: 1e7)
LEVER_LIMIT = 1e3


def fastest_input(scenario: Scenario, omega: float) -> tuple[str, str] | None:
    """The key of the spring-damper isolator whose stiffness, damping or lever arm most likely makes a mode as
    fast as ``omega`` [1/s], and why: the rates ``sqrt(k g)`` and ``c g`` with ``g = 1/m + r^2/I`` (total mass,
    distance from the mass centre, least principal inertia; the position named when its lever ``r^2 m / I``
    exceeds :data:`LEVER_LIMIT`); None when none reaches a tenth of ``omega``."""
    mass, inertia = scenario.total_mass, float(min(scenario.table.inertia))
    best: tuple[float, str, str] | None = None
    for i, iso in enumerate(scenario.isolators):
        if not isinstance(iso, Isolator):  # pneumatic: its stiffness is the air's
            continue
        r2 = float(np.dot(iso.position, iso.position))
        gain = 1.0 / mass + r2 / inertia
        arm = r2 * mass / inertia > LEVER_LIMIT
        for rate, kind, value, unit in ((math.sqrt(max(iso.stiffness) * gain), "stiffness", max(iso.stiffness),
                                         "N/m"), (max(iso.damping) * gain, "damping", max(iso.damping), "N s/m")):
            if best is None or rate > best[0]:
                if arm:
                    text = (f"it lies {math.sqrt(r2):.4g} m from the table's mass centre (inertia {inertia:.4g} "
                            f"kg m^2), a lever that makes its {kind} of {value:.3g} {unit} act "
                            f"{r2 * mass / inertia:.3g} times harder on the rotations (a position in mm? the table "
                            "frame is in m)")
                    best = (rate, f"isolators[{i}].position", text)
                else:
                    best = (rate, f"isolators[{i}].{kind}", f"{value:.3g} {unit} on a table of {mass:.4g} kg, far "
                                                            "beyond a real isolator's (or much too light a table)")
    if best is None or best[0] < 0.1 * omega:
        return None
    return best[1], best[2]
