"""Feedback controllers for the active table, designed on the linearised plant (python-control).

Every controller here maps the table's measured motion to actuator commands:

* measurements: the 12 states of :mod:`isolator.analysis.linear` (``x, y, z`` [m],
  ``rx, ry, rz`` [rad], ``vx .. wz`` [m/s, rad/s]; world axes, from the
  reference the controller regulates to), as ideal inertial sensors give them;
* outputs: one commanded force per actuator [N] (``actuator:<name>``).

Designs:

* :func:`skyhook`: absolute-velocity damping, each actuator pushing against
  the table's velocity at its own point along its own line (collocated, so
  passive: it cannot destabilise the continuous-time loop);
* :func:`pid` and :func:`lead`: the same collocated structure with a PID
  (filtered derivative) or a lead compensator on the absolute displacement;
* :func:`lqr`: full-state LQR by ``control.lqr`` with Bryson's rule weights;
* :func:`hinf`: H-infinity state-feedback-with-noise design by
  ``control.hinfsyn`` (needs slycot).

:func:`closed_loop` closes the loop on the linear plant (with the actuators'
first-order lag) for transmissibility and compliance with control;
:func:`check_stability` checks the loop in continuous time and as run, i.e.
the controller discretised (Tustin) at its sample rate around the plant held
by a zero-order hold, and raises :class:`~isolator.errors.UnstableClosedLoopError`.
The designs ignore the actuators' lag and saturation; the checks and the
simulation include them. No anti-windup: an integrator keeps integrating
while its actuator saturates.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import control
import numpy as np
from scipy.linalg import expm

from controllers.feedforward import QuasiStaticPath, allocation_matrix
from isolator.analysis.linear import (
    FORCE_INPUTS,
    GROUND_INPUTS,
    STATE_NAMES,
    LinearModel,
    is_stable,
    linearise,
    state_space_response,
)
from isolator.errors import ScenarioError, UnstableClosedLoopError
from isolator.model.rotations import pose_rotation
from isolator.scenario.definitions import SIGNALS, Scenario

__all__ = [
    "MEASUREMENTS",
    "REFERENCE_INPUTS",
    "ClosedLoop",
    "Controller",
    "DiscreteLaw",
    "LoopStability",
    "check_stability",
    "closed_loop",
    "decentralised",
    "feedback_law",
    "hinf",
    "lead",
    "lqr",
    "pid",
    "skyhook",
]

MEASUREMENTS = STATE_NAMES
REFERENCE_INPUTS = tuple(f"reference:{s}" for s in SIGNALS)
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
        if not (math.isfinite(self.sample_rate) and self.sample_rate > 0):
            raise ScenarioError(f"sample_rate: must be a finite rate > 0 Hz, got {self.sample_rate}")

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
    return allocation_matrix(lin.scenario, pose_rotation(lin.equilibrium.pose[3:])).T


def _actuator_labels(scenario: Scenario) -> list[str]:
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
    if measure not in ("displacement", "velocity"):
        raise ScenarioError(f"measure: must be 'displacement' or 'velocity', got '{measure}'")
    j = _collocation(lin)
    n_a = j.shape[0]
    pick = np.hstack([j, np.zeros_like(j)]) if measure == "displacement" else np.hstack([np.zeros_like(j), j])
    g = control.ss(transfer)
    a, b, c, d = (np.asarray(m, dtype=float) for m in (g.A, g.B, g.C, g.D))
    if b.shape[1] != 1 or c.shape[0] != 1:
        raise ScenarioError("transfer: must be a single-input single-output transfer function")
    eye = np.eye(n_a)
    system = control.ss(
        np.kron(eye, a), np.kron(eye, b) @ pick, -np.kron(eye, c), -np.kron(eye, d) @ pick,
        inputs=list(MEASUREMENTS), outputs=_actuator_labels(lin.scenario), name=name,
    )
    return Controller(name, system, sample_rate, description)


def _positive(value: float, key: str, allow_zero: bool = False) -> float:
    v = float(value)
    if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        raise ScenarioError(f"{key}: must be a finite number {'>=' if allow_zero else '>'} 0, got {value}")
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
        raise ScenarioError(f"pole_hz: must be above zero_hz ({fz:.4g} Hz) for a lead, got {fp}")
    wz, wp = 2 * math.pi * fz, 2 * math.pi * fp
    g = control.tf([k / wz, k], [1 / wp, 1.0])
    return decentralised(lin, g, "displacement", "lead", sample_rate,
                         f"lead {k:.4g} N/m, zero {fz:.4g} Hz, pole {fp:.4g} Hz")


def _actuated(lin: LinearModel) -> tuple[np.ndarray, np.ndarray]:
    """``A`` (12, 12) and ``B`` (12, n_a) of the table driven by its actuators."""
    sys = lin.system
    labels = list(sys.input_labels)
    cols = [labels.index(n) for n in _actuator_labels(lin.scenario)]
    return np.asarray(sys.A, dtype=float), np.asarray(sys.B, dtype=float)[:, cols]


def _scales(lin: LinearModel, max_displacement: float, max_rotation: float, max_velocity: float,
            max_rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Bryson's rule scales: acceptable size of each state and each actuator's ``max_force``."""
    states = [_positive(max_displacement, "max_displacement")] * 3 + [_positive(max_rotation, "max_rotation")] * 3
    states += [_positive(max_velocity, "max_velocity")] * 3 + [_positive(max_rate, "max_rate")] * 3
    return np.array(states), np.array([a.max_force for a in lin.scenario.actuators])


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
    a, b = _actuated(lin)
    sx, su = _scales(lin, max_displacement, max_rotation, max_velocity, max_rate)
    gain_scaled, _, _ = control.lqr(a * sx[None, :] / sx[:, None], b * su[None, :] / sx[:, None],
                                    np.eye(sx.size), np.eye(su.size))
    gain = su[:, None] * np.asarray(gain_scaled, dtype=float) / sx[None, :]
    system = control.ss(np.zeros((0, 0)), np.zeros((0, 12)), np.zeros((b.shape[1], 0)), -gain,
                        inputs=list(MEASUREMENTS), outputs=_actuator_labels(lin.scenario), name="lqr")
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
    ScenarioError
        slycot is missing, or no controller achieves a finite norm.
    """
    try:
        import slycot
    except ImportError:
        raise ScenarioError("hinf: needs slycot (pip install slycot)") from None
    a, b2 = _actuated(lin)
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
        raise ScenarioError(f"relax: must be >= 1 (a factor on the optimal norm), got {relax}")
    try:
        _, _, optimal, _ = control.hinfsyn(plant, n, m)
        out = slycot.sb10ad(n, 6 + n + m, 2 * n + m, m, n, factor * optimal, plant.A, plant.B, plant.C,
                            plant.D, job=4)
    except Exception as exc:  # slycot reports failures as its own exception types
        raise ScenarioError(f"hinf: no H-infinity controller for these weights ({exc})") from None
    gamma = factor * optimal
    k = control.ss(*out[1:5])
    # scaled measurement x / sx in, scaled force u / su out
    system = control.ss(k.A, np.asarray(k.B) / sx[None, :], su[:, None] * np.asarray(k.C),
                        su[:, None] * np.asarray(k.D) / sx[None, :], inputs=list(MEASUREMENTS),
                        outputs=_actuator_labels(lin.scenario), name="hinf")
    return Controller("hinf", system, sample_rate,
                      f"H-infinity, gamma {float(gamma):.3g}: Bryson weights {max_displacement:.3g} m, "
                      f"{max_rotation:.3g} rad, {max_velocity:.3g} m/s, {max_rate:.3g} rad/s; "
                      f"disturbance {d:.3g} N, noise {eps:.3g}")


# -- the loop on the linear plant ----------------------------------------------------------
@dataclass(frozen=True)
class _Plant:
    """The table with the actuators' lag, split for feedback (continuous time).

    States: the 12 table states then one lag state per actuator with a bandwidth.
    ``w`` = ground and force inputs; ``u`` = actuator commands; ``y`` = the
    linear model's outputs; ``m`` = the measured table states (true velocities).
    """

    a: np.ndarray
    bw: np.ndarray
    bu: np.ndarray
    cy: np.ndarray
    dyw: np.ndarray
    cm: np.ndarray
    dmw: np.ndarray
    inputs: list[str]
    outputs: list[str]


def _plant(lin: LinearModel) -> _Plant:
    sys = lin.system
    a, b = np.asarray(sys.A, dtype=float), np.asarray(sys.B, dtype=float)
    c, d = np.asarray(sys.C, dtype=float), np.asarray(sys.D, dtype=float)
    labels = list(sys.input_labels)
    w_names = [*GROUND_INPUTS, *FORCE_INPUTS]
    iw = [labels.index(x) for x in w_names]
    iu = [labels.index(x) for x in _actuator_labels(lin.scenario)]
    acts = lin.scenario.actuators
    lagged = [k for k, act in enumerate(acts) if act.bandwidth is not None]
    nl, n_a = len(lagged), len(acts)
    # lag states f_k' = (u_k - f_k) / tau_k drive the table through the actuator columns
    tau = np.array([1.0 / (2 * math.pi * acts[k].bandwidth) for k in lagged])  # type: ignore[operator]
    bu_table = b[:, iu]
    a_full = np.zeros((12 + nl, 12 + nl))
    a_full[:12, :12] = a
    a_full[:12, 12:] = bu_table[:, lagged]
    a_full[12:, 12:] = -np.diag(1.0 / tau)
    bu = np.zeros((12 + nl, n_a))
    direct = [k for k in range(n_a) if k not in lagged]
    bu[:12, direct] = bu_table[:, direct]
    bu[12 + np.arange(nl), lagged] = 1.0 / tau
    bw = np.vstack([b[:, iw], np.zeros((nl, len(iw)))])
    cy = np.hstack([c, np.zeros((c.shape[0], nl))])
    # the sensors see the true velocity, the state plus the floor's damper feedthrough: x = xi + B1 g
    cm = np.hstack([np.eye(12), np.zeros((12, nl))])
    dmw = lin.feedthrough[:, iw]
    return _Plant(a_full, bw, bu, cy, d[:, iw], cm, dmw, w_names, list(sys.output_labels))


@dataclass(frozen=True)
class ClosedLoop:
    """The linear plant with a controller in the loop (continuous time).

    Attributes
    ----------
    lin : LinearModel
        The open-loop plant.
    controller : Controller
    system : control.StateSpace
        Inputs ``ground:*``, ``force:*`` and ``reference:x .. rz`` (the
        controller's position reference); outputs those of ``lin``.
    """

    lin: LinearModel
    controller: Controller
    system: control.StateSpace

    @property
    def scenario(self) -> Scenario:
        return self.lin.scenario

    @property
    def eigenvalues(self) -> np.ndarray:
        return np.linalg.eigvals(np.asarray(self.system.A))

    def frequency_response(
        self, frequency_hz: np.ndarray, inputs: Sequence[str] | None = None, outputs: Sequence[str] | None = None
    ) -> np.ndarray:
        """Complex ``H(j 2 pi f)``, shape (nf, outputs, inputs) (see :meth:`LinearModel.frequency_response`)."""
        return state_space_response(self.system, frequency_hz, inputs, outputs)

    def dc_gain(self, inputs: Sequence[str], outputs: Sequence[str] = SIGNALS) -> np.ndarray:
        """Static gain from ``inputs`` to ``outputs``."""
        return np.real(self.frequency_response(np.array([0.0]), inputs, outputs)[0])


def closed_loop(lin: LinearModel, controller: Controller, check: bool = True) -> ClosedLoop:
    """Close the loop on the linear plant (actuator lag included, continuous time).

    Raises
    ------
    UnstableClosedLoopError
        With ``check``: the loop is unstable in continuous time or at the
        controller's sample rate.
    """
    p = _plant(lin)
    k = controller.system
    if list(k.output_labels) != _actuator_labels(lin.scenario) or list(k.input_labels) != list(MEASUREMENTS):
        raise ScenarioError("controller: was designed for other actuators or measurements than this plant's")
    _, bk, _, dk = (np.asarray(m, dtype=float) for m in (k.A, k.B, k.C, k.D))
    nk = bk.shape[0]
    # m = Cm x + Dmw w - [ref; 0];  u = Ck xc + Dk m
    ref = np.vstack([np.eye(6), np.zeros((6, 6))])
    a = _loop_matrix(p, controller)
    b = np.block([[p.bw + p.bu @ dk @ p.dmw, -p.bu @ dk @ ref], [bk @ p.dmw, -bk @ ref]])
    c = np.hstack([p.cy, np.zeros((p.cy.shape[0], nk))])
    d = np.hstack([p.dyw, np.zeros((p.cy.shape[0], 6))])
    system = control.ss(a, b, c, d, inputs=[*p.inputs, *REFERENCE_INPUTS], outputs=p.outputs,
                        name=f"{lin.scenario.name} with {controller.name}")
    loop = ClosedLoop(lin, controller, system)
    if check:
        _stability(lin, p, controller, a).raise_if_unstable()
    return loop


def _loop_matrix(p: _Plant, controller: Controller) -> np.ndarray:
    """State matrix of plant and controller in a loop (continuous time), states ``[x, x_c]``."""
    ak, bk, ck, dk = (np.asarray(m, dtype=float) for m in (controller.system.A, controller.system.B,
                                                          controller.system.C, controller.system.D))
    return np.block([[p.a + p.bu @ dk @ p.cm, p.bu @ ck], [bk @ p.cm, ak]])


@dataclass(frozen=True)
class LoopStability:
    """Stability of a loop in continuous time and as sampled.

    Attributes
    ----------
    continuous : ndarray
        Closed-loop eigenvalues [1/s].
    sampled : ndarray
        Eigenvalues of the sampled loop (plant held by a zero-order hold,
        controller by Tustin) over one controller period.
    sample_rate : float
        [Hz]
    where : str
        The configuration checked, in words.
    """

    continuous: np.ndarray
    sampled: np.ndarray
    sample_rate: float
    controller: str
    where: str = ""
    stable: bool = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "stable", is_stable(self.continuous) and self.spectral_radius < 1.0)

    @property
    def spectral_radius(self) -> float:
        return float(np.max(np.abs(self.sampled), initial=0.0))

    @property
    def margin(self) -> float:
        """Slowest decay of the continuous loop [1/s] (-max Re s; negative when unstable)."""
        return float(-np.max(self.continuous.real))

    def raise_if_unstable(self) -> None:
        if self.stable:
            return
        worst = self.continuous[np.argmax(self.continuous.real)]
        raise UnstableClosedLoopError(
            f"the closed loop with {self.controller} is unstable {self.where}: "
            f"largest |z| = {self.spectral_radius:.4g} at {self.sample_rate:.4g} Hz sampling; continuous-time "
            f"eigenvalue {worst.real:.4g}{worst.imag:+.4g}j 1/s ({abs(worst.imag) / (2 * math.pi):.3g} Hz). "
            "Lower the gains or raise the sample rate."
        )

    def to_dict(self) -> dict[str, Any]:
        return {"stable": self.stable, "spectral_radius": self.spectral_radius, "margin": self.margin,
                "sample_rate": self.sample_rate}


def check_stability(lin: LinearModel, controller: Controller, where: str = "") -> LoopStability:
    """Check the loop of ``controller`` around ``lin`` continuous and sampled."""
    p = _plant(lin)
    return _stability(lin, p, controller, _loop_matrix(p, controller), where)


def _stability(lin: LinearModel, p: _Plant, controller: Controller, a_cont: np.ndarray,
               where: str = "") -> LoopStability:
    """The loop's eigenvalues: ``a_cont`` (from :func:`_loop_matrix`) and the sampled loop's."""
    n = p.a.shape[0]
    h = 1.0 / controller.sample_rate
    m_u = p.bu.shape[1]
    big = np.zeros((n + m_u, n + m_u))
    big[:n, :n], big[:n, n:] = p.a * h, p.bu * h
    e = expm(big)
    phi, gam = e[:n, :n], e[:n, n:]
    kad, kbd, kcd, kdd = controller.discrete()
    # u_k = Ckd xc_k + Dkd m_k held over the period; x_{k+1} = Phi x_k + Gamma u_k; xc_{k+1} = Akd xc + Bkd m_k
    a_disc = np.block([[phi + gam @ kdd @ p.cm, gam @ kcd], [kbd @ p.cm, kad]])
    where = where or f"with the carriages at {', '.join(f'{q:.4g}' for q in lin.positions)} m"
    return LoopStability(np.linalg.eigvals(a_cont), np.linalg.eigvals(a_disc), controller.sample_rate,
                         controller.name, where)


# -- the law the simulation runs -----------------------------------------------------------
class DiscreteLaw:
    """A controller as the time-varying simulation runs it.

    At each tick ``t_k = k / sample_rate`` it measures the table's deviation
    from its reference (the initial equilibrium, or a quasi-static path and
    its rate), updates the Tustin-discretised controller and returns the
    command, which the simulation holds until the next tick (adding any
    feedforward, then saturating and lagging as the actuators do).
    Build it with :func:`feedback_law`.

    Parameters
    ----------
    controller : Controller
    reference : QuasiStaticPath, optional
        What the controller regulates to (default: the initial equilibrium).
    end : ClosedLoop, optional
        The loop with the carriages at their final positions, for the
        closed-loop final value (default: the passive one).
    """

    def __init__(self, controller: Controller, reference: QuasiStaticPath | None = None,
                 end: ClosedLoop | None = None) -> None:
        self.controller = controller
        self.reference = reference
        self.end = end
        self.sample_rate = controller.sample_rate
        self.ad, self.bd, self.cd, self.dd = controller.discrete()
        self.state = np.zeros(self.ad.shape[0])

    def reset(self) -> None:
        self.state = np.zeros(self.ad.shape[0])

    def _reference(self, t: float) -> np.ndarray:
        if self.reference is None:
            return np.zeros(12)
        tt = np.array([t])
        return np.concatenate([self.reference(tt)[0], self.reference(tt, None, 1)[0]])

    def __call__(self, t: float, measurement: np.ndarray) -> np.ndarray:
        """Command [N] per actuator at a tick from the measured state (12,) relative to the start."""
        m = np.asarray(measurement, dtype=float) - self._reference(t)
        u = self.cd @ self.state + self.dd @ m
        self.state = self.ad @ self.state + self.bd @ m
        return u

    def final(self, passive: np.ndarray) -> np.ndarray:
        """Closed-loop final value of the six signals from the passive one (linear, at the end)."""
        if self.end is None:
            return np.asarray(passive, dtype=float)
        r_end = self._reference(math.inf)[:6] if self.reference is not None else np.zeros(6)
        return passive + self.end.dc_gain(REFERENCE_INPUTS) @ (r_end - passive)


def feedback_law(
    scenario: Scenario, controller: Controller, reference: QuasiStaticPath | None = None, check: bool = True
) -> DiscreteLaw:
    """The controller ready to run in the simulation of ``scenario``, its loop checked.

    Parameters
    ----------
    reference : QuasiStaticPath, optional
        Regulate to this path (e.g. the feedforward's) instead of the initial
        equilibrium, so that feedback does not fight the quasi-static tilt.
    check : bool
        Raise :class:`UnstableClosedLoopError` when the sampled loop is unstable
        with the carriages at their start or their final positions.
    """
    lin_start = linearise(scenario)
    finals = scenario.final_positions()
    lin_end = linearise(scenario, positions=finals) if finals is not None else lin_start
    if check:
        check_stability(lin_start, controller, "with the carriages at their start").raise_if_unstable()
        check_stability(lin_end, controller, "with the carriages at their final positions").raise_if_unstable()
    return DiscreteLaw(controller, reference, closed_loop(lin_end, controller, check=False))
