"""Feedback designs on the linearised plant (python-control), and the controller they return.

* :func:`skyhook`: absolute-velocity damping, each actuator pushing against
  the table's velocity at its own point along its own line (collocated, so
  passive: it cannot destabilise the continuous-time loop);
* :func:`pid` and :func:`lead`: the same collocated structure with a PID
  (filtered derivative) or a lead compensator on the absolute displacement
  (:func:`decentralised`: any SISO law that way);
* :func:`lqr`: full-state LQR by ``control.lqr`` with Bryson's rule weights;
* :func:`hinf`: H-infinity state-feedback-with-noise design by
  ``control.hinfsyn`` (needs slycot).

The designs ignore the actuators' lag and saturation; the checks
(:mod:`controllers.feedback.loops`) and the simulation include them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np

from controllers.feedforward.wrench import allocation_matrix
from isolator.analysis.linear import FORCE_INPUTS, STATE_NAMES, LinearModel
from isolator.errors import OptimisationError, ParameterError, ScenarioError
from isolator.model.rotations import pose_rotation
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.rules import check_value

__all__ = ["MEASUREMENTS", "SAMPLE_RATE", "Controller", "decentralised", "hinf", "lead", "lqr", "pid", "skyhook"]

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
    """

    name: str
    system: control.StateSpace
    sample_rate: float = SAMPLE_RATE
    description: str = ""

    def __post_init__(self) -> None:
        rate = check_value("sample_rate", self.sample_rate, "sample_rate", ParameterError)
        if not rate > 0:
            raise ParameterError(f"sample_rate: must be a finite rate > 0 Hz, got {self.sample_rate}")
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
        inputs=list(MEASUREMENTS), outputs=actuator_labels(lin.scenario), name=name,
    )
    return Controller(name, system, sample_rate, description)


def _positive(value: float, key: str, allow_zero: bool = False) -> float:
    v = check_value(key, value, key, ParameterError)
    if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        raise ParameterError(f"{key}: must be a finite number {'>=' if allow_zero else '>'} 0, got {value}")
    return v


def skyhook(lin: LinearModel, damping: float, sample_rate: float = SAMPLE_RATE) -> Controller:
    """Skyhook damping: every actuator ``f = -c v`` on the absolute velocity at its point.

    Parameters
    ----------
    damping : float
        ``c`` per actuator [N s/m].
    """
    c = _positive(damping, "damping")
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
    """Collocated PID on the absolute displacement: ``kp + ki/s + kd s / (1 + s/w_f)``.

    Parameters
    ----------
    kp : float
        [N/m] (added stiffness).
    ki : float
        [N/(m s)]; > 0 holds the table at the reference (also against the
        quasi-static tilt of a move: large standing forces).
    kd : float
        [N s/m] (added damping).
    derivative_filter_hz : float
        Corner of the derivative's low-pass [Hz].
    """
    kp, ki, kd = (_positive(v, k, allow_zero=True) for v, k in ((kp, "kp"), (ki, "ki"), (kd, "kd")))
    wf = 2 * math.pi * _positive(derivative_filter_hz, "derivative_filter_hz")
    s = control.tf("s")
    g = kp + kd * s / (1 + s / wf)
    if ki > 0:
        g = g + ki / s
    return decentralised(lin, control.tf(g), "displacement", "pid", sample_rate,
                         f"PID kp {kp:.4g} N/m, ki {ki:.4g} N/(m s), kd {kd:.4g} N s/m, "
                         f"derivative filter {derivative_filter_hz:.4g} Hz")


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
    """
    k = _positive(gain, "gain")
    fz, fp = _positive(zero_hz, "zero_hz"), _positive(pole_hz, "pole_hz")
    if fp <= fz:
        raise ParameterError(f"pole_hz: must be above zero_hz ({fz:.4g} Hz) for a lead, got {fp}")
    wz, wp = 2 * math.pi * fz, 2 * math.pi * fp
    g = control.tf([k / wz, k], [1 / wp, 1.0])
    return decentralised(lin, g, "displacement", "lead", sample_rate,
                         f"lead {k:.4g} N/m, zero {fz:.4g} Hz, pole {fp:.4g} Hz")


def actuated(lin: LinearModel) -> tuple[np.ndarray, np.ndarray]:
    """``A`` (12, 12) and ``B`` (12, n_a) of the table driven by its actuators."""
    sys = lin.system
    labels = list(sys.input_labels)
    cols = [labels.index(n) for n in actuator_labels(lin.scenario)]
    return np.asarray(sys.A, dtype=float), np.asarray(sys.B, dtype=float)[:, cols]


def _scales(lin: LinearModel, max_displacement: float, max_rotation: float, max_velocity: float,
            max_rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Bryson's rule scales: acceptable size of each state and each actuator's ``max_force``."""
    states = [_positive(max_displacement, "max_displacement")] * 3 + [_positive(max_rotation, "max_rotation")] * 3
    states += [_positive(max_velocity, "max_velocity")] * 3 + [_positive(max_rate, "max_rate")] * 3
    return np.array(states), np.array([a.max_force for a in lin.scenario.actuators])


def _measured_state(lin: LinearModel, name: str) -> None:
    """State-feedback designs need the whole state among the measurements (the table's 12 states)."""
    if lin.air is not None:
        raise ParameterError(
            f"controller: {name} feeds back the whole state, and a pneumatic table's chamber pressures are not "
            "measured (use skyhook, pid or lead)"
        )


def lqr(
    lin: LinearModel,
    max_displacement: float = 1e-4,
    max_rotation: float = 1e-4,
    max_velocity: float = 1e-3,
    max_rate: float = 1e-3,
    sample_rate: float = SAMPLE_RATE,
) -> Controller:
    """Full-state LQR (``control.lqr``) with Bryson's rule weights.

    ``Q = diag(1 / max_i^2)`` on the 12 states, ``R = diag(1 / max_force^2)``
    per actuator; ``u = -K x``. The Riccati equation is solved in states and
    forces scaled by those sizes (the same gain, well conditioned).

    Parameters
    ----------
    max_displacement, max_rotation, max_velocity, max_rate : float
        Acceptable table displacement [m], rotation [rad], velocity [m/s] and
        angular velocity [rad/s].
    """
    _measured_state(lin, "lqr")
    a, b = actuated(lin)
    sx, su = _scales(lin, max_displacement, max_rotation, max_velocity, max_rate)
    gain_scaled, _, _ = control.lqr(a * sx[None, :] / sx[:, None], b * su[None, :] / sx[:, None],
                                    np.eye(sx.size), np.eye(su.size))
    gain = su[:, None] * np.asarray(gain_scaled, dtype=float) / sx[None, :]
    system = control.ss(np.zeros((0, 0)), np.zeros((0, 12)), np.zeros((b.shape[1], 0)), -gain,
                        inputs=list(MEASUREMENTS), outputs=actuator_labels(lin.scenario), name="lqr")
    return Controller("lqr", system, sample_rate,
                      f"LQR, Bryson weights: {max_displacement:.3g} m, {max_rotation:.3g} rad, "
                      f"{max_velocity:.3g} m/s, {max_rate:.3g} rad/s, max_force per actuator")


def hinf(
    lin: LinearModel,
    max_displacement: float = 1e-3,
    max_rotation: float = 1e-3,
    max_velocity: float = 1e-2,
    max_rate: float = 1e-2,
    disturbance: float = 100.0,
    noise: float = 0.1,
    relax: float = 1.5,
    sample_rate: float = SAMPLE_RATE,
) -> Controller:
    """H-infinity output feedback (``control.hinfsyn``, needs slycot).

    Generalised plant, in states and forces scaled as in :func:`lqr`: a
    wrench disturbance at the mass centre (``disturbance`` N and N m per
    axis) and sensor noise (``noise``, a fraction of each state's acceptable
    size) in; the scaled states and forces out; the noisy states measured.
    ``control.hinfsyn`` finds the optimal norm ``gamma``; the controller is
    the central suboptimal one at ``relax * gamma`` (slycot ``sb10ad``): the
    optimal one has poles far beyond any sample rate.

    Raises
    ------
    ParameterError
        slycot is missing, or a weight is not a finite positive number.
    OptimisationError
        No controller achieves a finite norm.
    """
    try:
        import slycot
    except ImportError:
        raise ParameterError('controller: hinf needs slycot: pip install ".[hinf]" (the extra "hinf"; or pip '
                             "install slycot)") from None
    _measured_state(lin, "hinf")
    a, b2 = actuated(lin)
    labels = list(lin.system.input_labels)
    bw = np.asarray(lin.system.B, dtype=float)[:, [labels.index(n) for n in FORCE_INPUTS]]
    d = _positive(disturbance, "disturbance")
    eps = _positive(noise, "noise")
    sx, su = _scales(lin, max_displacement, max_rotation, max_velocity, max_rate)
    n, m = a.shape[0], b2.shape[1]
    a_s = a * sx[None, :] / sx[:, None]
    b1 = np.hstack([bw * d / sx[:, None], np.zeros((n, n))])
    b2_s = b2 * su[None, :] / sx[:, None]
    c1 = np.vstack([np.eye(n), np.zeros((m, n))])
    d12 = np.vstack([np.zeros((n, m)), np.eye(m)])
    d21 = np.hstack([np.zeros((n, 6)), eps * np.eye(n)])
    plant = control.ss(a_s, np.hstack([b1, b2_s]), np.vstack([c1, np.eye(n)]),
                       np.block([[np.zeros((n + m, 6 + n)), d12], [d21, np.zeros((n, m))]]))
    factor = _positive(relax, "relax")
    if factor < 1:
        raise ParameterError(f"relax: must be >= 1 (a factor on the optimal norm), got {relax}")
    try:
        _, _, optimal, _ = control.hinfsyn(plant, n, m)
        out = slycot.sb10ad(n, 6 + n + m, 2 * n + m, m, n, factor * optimal, plant.A, plant.B, plant.C,
                            plant.D, job=4)
    except Exception as exc:  # slycot reports failures as its own exception types
        raise OptimisationError(f"hinf: no H-infinity controller for these weights ({exc})") from None
    gamma = factor * optimal
    k = control.ss(*out[1:5])
    # scaled measurement x / sx in, scaled force u / su out
    system = control.ss(k.A, np.asarray(k.B) / sx[None, :], su[:, None] * np.asarray(k.C),
                        su[:, None] * np.asarray(k.D) / sx[None, :], inputs=list(MEASUREMENTS),
                        outputs=actuator_labels(lin.scenario), name="hinf")
    return Controller("hinf", system, sample_rate,
                      f"H-infinity, gamma {float(gamma):.3g}: Bryson weights {max_displacement:.3g} m, "
                      f"{max_rotation:.3g} rad, {max_velocity:.3g} m/s, {max_rate:.3g} rad/s; "
                      f"disturbance {d:.3g} N, noise {eps:.3g}")


check_public(globals())
