"""Feedback designs on the linearised plant (python-control), and the controller they return.

* :func:`skyhook`: absolute-velocity damping, each actuator pushing against
  the table's velocity at its own point along its own line (collocated, so
  passive: it cannot destabilise the continuous-time loop);
* :func:`pid` and :func:`lead`: the same collocated structure with a PID
  (filtered derivative; its integral action one integrator per controlled
  direction of the table, not per actuator) or a lead compensator on the
  absolute displacement (:func:`decentralised`: any SISO law that way);
* the state-feedback designs :func:`~controllers.feedback.state_designs.lqr` and
  :func:`~controllers.feedback.state_designs.hinf` are in
  :mod:`controllers.feedback.state_designs`, on :func:`actuated` and the
  Bryson scales here.

The two state-feedback designs regulate the table's absolute position, so
they run about the quasi-static path of the carriages' weight
(:attr:`Controller.follows_path`), not about the initial equilibrium.

The designs ignore the actuators' lag and saturation; the checks
(:mod:`controllers.feedback.loops`) and the simulation include them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import control
import numpy as np

from controllers.feedforward.wrench import allocation_matrix
from isolator.analysis.linear import STATE_NAMES, LinearModel
from isolator.analysis.sampling import check_sample_rate
from isolator.analysis.signal_names import labels, signals, to_control
from isolator.errors import ParameterError, ScenarioError
from isolator.model.rotations import pose_rotation
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.rules import check_value

__all__ = ["MEASUREMENTS", "SAMPLE_RATE", "Controller", "as_given", "decentralised", "lead", "per_axis", "pid",
           "positive", "skyhook"]

MEASUREMENTS = STATE_NAMES
#: default controller sample rate [Hz]
SAMPLE_RATE = 1000.0


@dataclass(frozen=True)
class Controller:
    """A continuous-time design and the rate it runs at.

    Attributes
    ----------
    name : str
        e.g. ``"skyhook"``, ``"lqr"``.
    system : control.StateSpace
        Inputs :data:`MEASUREMENTS` (deviation from the reference), outputs
        ``actuator:<name>`` [N]. Negative feedback is built in: the outputs are
        the commands themselves.
    sample_rate : float
        [Hz] at which it is run (discretised by Tustin's method).
    description : str
        The design's parameters, in words.
    follows_path : bool
        The design regulates the table's absolute position states (its weights
        allow micrometres), so regulated about the initial equilibrium it
        fights the quasi-static tilt of a carriage's weight crossing the table
        with large standing forces. True: run it about the carriages'
        quasi-static path (:func:`~controllers.feedback.feedback_law` then
        defaults its ``reference`` to ``quasi_static_path(scenario)``; the
        static tilt is left to the isolators, as with feedforward).
        ``dataclasses.replace(controller, follows_path=False)`` restores the
        initial equilibrium as the default reference.
    """

    name: str
    system: control.StateSpace
    sample_rate: float = SAMPLE_RATE
    description: str = ""
    follows_path: bool = False

    def __post_init__(self) -> None:
        check_sample_rate(self.sample_rate)
        if not isinstance(self.system, control.StateSpace):
            raise ParameterError(f"system: must be a control.StateSpace, got {type(self.system).__name__}")

    def discrete(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` of the controller discretised by Tustin's method at :attr:`sample_rate`."""
        a, b, c, d = (np.asarray(m, dtype=float) for m in (self.system.A, self.system.B,
                                                           self.system.C, self.system.D))
        n = a.shape[0]
        if n == 0:
            return a, np.zeros((0, b.shape[1])), np.zeros((c.shape[0], 0)), d
        h = 1.0 / self.sample_rate
        eye = np.eye(n)
        left = np.linalg.inv(eye - a * h / 2)
        ad = left @ (eye + a * h / 2)
        bd = left @ b * h
        cd = c @ left
        dd = d + c @ left @ b * h / 2
        return ad, bd, cd, dd


# -- designs -----------------------------------------------------------------------------
def _collocation(lin: LinearModel) -> np.ndarray:
    """``J`` (n_a, 6): each actuator's displacement along its line per table displacement and rotation."""
    if not lin.scenario.actuators:
        raise ScenarioError("actuators: the scenario has no [[actuators]] to control with")
    return allocation_matrix(lin.scenario, pose_rotation(lin.equilibrium.pose[3:6])).T


def actuator_labels(scenario: Scenario) -> list[str]:
    return [f"actuator:{a.name}" for a in scenario.actuators]


def decentralised(
    lin: LinearModel,
    transfer: control.TransferFunction,
    measure: str,
    name: str,
    sample_rate: float = SAMPLE_RATE,
    description: str = "",
) -> Controller:
    """The same SISO law at every actuator on its collocated displacement or velocity.

    ``f_i = -G(s) y_i`` with ``y_i`` the table's absolute displacement (or
    velocity) at actuator ``i``'s point along its line.

    Parameters
    ----------
    lin : LinearModel
        Plant at the design configuration (its actuators' geometry is used).
    transfer : control.TransferFunction
        ``G(s)``, proper, in N/m (displacement) or N s/m (velocity).
    measure : {"displacement", "velocity"}
    name : str
        The design's name (``skyhook``, ``pid``, ``lead``).
    sample_rate : float
        The rate the controller runs at in the simulation [Hz].
    description : str
        How the design is described in reports.

    Returns
    -------
    Controller
        The continuous-time design and its sample rate.
    """
    if not isinstance(transfer, control.TransferFunction | control.StateSpace):
        raise ParameterError(f"transfer: must be a control.TransferFunction, got {type(transfer).__name__}")
    if measure not in ("displacement", "velocity"):
        raise ParameterError(f"measure: must be 'displacement' or 'velocity', got '{measure}'")
    j = _collocation(lin)
    n_a = j.shape[0]
    pick = np.hstack([j, np.zeros_like(j)]) if measure == "displacement" else np.hstack([np.zeros_like(j), j])
    g = control.ss(transfer)
    a, b, c, d = (np.asarray(m, dtype=float) for m in (g.A, g.B, g.C, g.D))
    if b.shape[1] != 1 or c.shape[0] != 1:
        raise ParameterError("transfer: must be a single-input single-output transfer function")
    eye = np.eye(n_a)
    system = control.ss(
        np.kron(eye, a), np.kron(eye, b) @ pick, -np.kron(eye, c), -np.kron(eye, d) @ pick,
        inputs=list(MEASUREMENTS), outputs=signals(actuator_labels(lin.scenario)), name=to_control(name),
    )
    return Controller(name, system, sample_rate, description)


def positive(value: float, key: str, allow_zero: bool = False) -> float:
    """``value`` as a float, or a :class:`ParameterError` naming ``key`` unless it is finite and > 0 (``>= 0``
    with ``allow_zero``): the check of every design setting."""
    v = check_value(key, value, key, ParameterError)
    if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        raise ParameterError(f"{key}: must be a finite number {'>=' if allow_zero else '>'} 0, got {value}")
    return v


def per_axis(value: float | Sequence[float], key: str) -> np.ndarray:
    """A setting given once or per world axis (x, y, z) as three positive numbers (3,), or a
    :class:`ParameterError` naming ``key``."""
    if isinstance(value, Sequence) and not isinstance(value, str):
        if len(value) != 3:
            raise ParameterError(f"{key}: must be a number or three (x, y, z), got {len(value)}")
        return np.array([positive(v, f"{key}[{k}]") for k, v in enumerate(value)])
    return np.full(3, positive(value, key))


def as_given(values: np.ndarray) -> float | list[float]:
    """A per-axis setting as JSON: one number when the three agree."""
    return float(values[0]) if np.all(values == values[0]) else [float(v) for v in values]


def skyhook(lin: LinearModel, damping: float, sample_rate: float = SAMPLE_RATE) -> Controller:
    """Skyhook damping: every actuator ``f = -c v`` on the absolute velocity at its point.

    Parameters
    ----------
    damping : float
        ``c`` per actuator [N s/m].
    lin : LinearModel
        The plant linearised at the design configuration, with ``[[actuators]]`` (their geometry, limits and
        lag are used).
    sample_rate : float
        The rate the controller runs at in the simulation [Hz].

    Returns
    -------
    Controller
        The continuous-time design and its sample rate.
    """
    c = positive(damping, "damping")
    return decentralised(lin, control.tf([c], [1.0]), "velocity", "skyhook", sample_rate,
                         f"skyhook damping {c:.4g} N s/m per actuator")


def pid(
    lin: LinearModel,
    kp: float,
    ki: float = 0.0,
    kd: float = 0.0,
    derivative_filter_hz: float = 100.0,
    sample_rate: float = SAMPLE_RATE,
) -> Controller:
    """Collocated PID on the absolute displacement: ``kp + kd s / (1 + s/w_f)`` per actuator, ``ki / s`` per
    controlled direction.

    The proportional and derivative parts act at each actuator on its
    collocated displacement ``y = J x`` (``J`` = the allocation matrix's
    transpose). The integral action has one integrator per direction the
    actuators control (the six rigid-body directions when ``J`` has full
    rank): the table's displacement and rotation ``J^+ y`` (the allocation's
    pseudo-inverse) integrated, the integral distributed back over the
    actuators by ``J``: ``u_I = -ki J integral(J^+ y)``. Its wrench
    ``-ki J^T J integral(x)`` is that of ``ki / s`` at every actuator, but
    redundant actuators (12 for 6 directions) add no integrators the table
    cannot tell apart: one per actuator would leave ``n_actuators - rank J``
    closed-loop eigenvalues at zero (marginal modes, their integrators
    pushing the actuators against each other).

    Parameters
    ----------
    kp : float
        [N/m] (added stiffness per actuator).
    ki : float
        [N/(m s)] per actuator along each controlled direction (the wrench
        ``ki J^T J`` per unit of the integrated displacement [m s] and
        rotation [rad s]); > 0 holds the table at the reference (also
        against the quasi-static tilt of a move: large standing forces) and
        rejects a constant disturbance force along every controlled direction.
    kd : float
        [N s/m] (added damping).
    derivative_filter_hz : float
        Corner of the derivative's low-pass [Hz].
    lin : LinearModel
        The plant linearised at the design configuration, with ``[[actuators]]`` (their geometry, limits and
        lag are used).
    sample_rate : float
        The rate the controller runs at in the simulation [Hz].

    Returns
    -------
    Controller
        The continuous-time design and its sample rate.
    """
    kp, ki, kd = (positive(v, k, allow_zero=True) for v, k in ((kp, "kp"), (ki, "ki"), (kd, "kd")))
    wf = 2 * math.pi * positive(derivative_filter_hz, "derivative_filter_hz")
    s = control.tf("s")
    description = (f"PID kp {kp:.4g} N/m, ki {ki:.4g} N/(m s), kd {kd:.4g} N s/m, "
                   f"derivative filter {derivative_filter_hz:.4g} Hz")
    local = decentralised(lin, control.tf(kp + kd * s / (1 + s / wf)), "displacement", "pid", sample_rate,
                          description)
    if ki == 0:
        return local
    j = _collocation(lin)
    u_, sv, vt = np.linalg.svd(j, full_matrices=False)
    rank = int(np.sum(sv > 1e-9 * sv[0]))
    # integrated coordinates: the table's displacement and rotation when J has full rank, else its
    # controlled directions (orthonormal combinations of them)
    basis = np.eye(6) if rank == 6 else vt[:rank].T
    to_dirs = basis.T @ vt[:rank].T @ np.diag(1 / sv[:rank]) @ u_[:, :rank].T  # basis^T J^+ (rank, n_a)
    k = local.system
    a, b, c, d = (np.asarray(m, dtype=float) for m in (k.A, k.B, k.C, k.D))
    n = a.shape[0]
    pick = np.hstack([j, np.zeros_like(j)])  # y = J x from the 12 measured states
    system = control.ss(
        np.block([[a, np.zeros((n, rank))], [np.zeros((rank, n)), np.zeros((rank, rank))]]),
        np.vstack([b, to_dirs @ pick]), np.hstack([c, -ki * j @ basis]), d,
        inputs=list(MEASUREMENTS), outputs=signals(actuator_labels(lin.scenario)), name="pid",
    )
    return Controller("pid", system, sample_rate, description)


def lead(
    lin: LinearModel,
    gain: float,
    zero_hz: float,
    pole_hz: float,
    sample_rate: float = SAMPLE_RATE,
) -> Controller:
    """Collocated lead compensator on the absolute displacement: ``k (1 + s/w_z) / (1 + s/w_p)``.

    Parameters
    ----------
    gain : float
        Low-frequency stiffness ``k`` [N/m].
    zero_hz, pole_hz : float
        Corners [Hz], zero below pole (most phase lead at their geometric mean;
        above the pole it acts as damping ``k / w_z`` plus stiffness).
    lin : LinearModel
        The plant linearised at the design configuration, with ``[[actuators]]`` (their geometry, limits and
        lag are used).
    sample_rate : float
        The rate the controller runs at in the simulation [Hz].

    Returns
    -------
    Controller
        The continuous-time design and its sample rate.
    """
    k = positive(gain, "gain")
    fz, fp = positive(zero_hz, "zero_hz"), positive(pole_hz, "pole_hz")
    if fp <= fz:
        raise ParameterError(f"pole_hz: must be above zero_hz ({fz:.4g} Hz) for a lead, got {fp}")
    wz, wp = 2 * math.pi * fz, 2 * math.pi * fp
    g = control.tf([k / wz, k], [1 / wp, 1.0])
    return decentralised(lin, g, "displacement", "lead", sample_rate,
                         f"lead {k:.4g} N/m, zero {fz:.4g} Hz, pole {fp:.4g} Hz")


def actuated(lin: LinearModel) -> tuple[np.ndarray, np.ndarray]:
    """``A`` (12, 12) and ``B`` (12, n_a) of the table driven by its actuators."""
    sys = lin.system
    names = labels(sys.input_labels)
    cols = [names.index(n) for n in actuator_labels(lin.scenario)]
    return np.asarray(sys.A, dtype=float), np.asarray(sys.B, dtype=float)[:, cols]


def _scales(lin: LinearModel, max_displacement: float, max_rotation: float, max_velocity: float,
            max_rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Bryson's rule scales: acceptable size of each state and each actuator's ``max_force``."""
    states = [positive(max_displacement, "max_displacement")] * 3 + [positive(max_rotation, "max_rotation")] * 3
    states += [positive(max_velocity, "max_velocity")] * 3 + [positive(max_rate, "max_rate")] * 3
    return np.array(states), np.array([a.max_force for a in lin.scenario.actuators])


def _measured_state(lin: LinearModel, name: str) -> None:
    """State-feedback designs need the whole state among the measurements (the table's 12 states)."""
    if lin.air is not None:
        raise ParameterError(
            f"controller: {name} feeds back the whole state, and a pneumatic table's chamber pressures are not "
            "measured (use skyhook, pid or lead)"
        )


check_public(globals())
