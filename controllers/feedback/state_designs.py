"""The state-feedback designs: full-state LQR and H-infinity on the linearised plant (python-control).

* :func:`lqr`: full-state LQR by ``control.lqr`` with Bryson's rule weights;
* :func:`hinf`: H-infinity state-feedback-with-noise design by
  ``control.hinfsyn`` (needs slycot).

Both regulate the table's absolute position and attitude to micrometres and
microradians, while a carriage's weight crossing the table tilts it
quasi-statically by far more (paper-table-3-2-active: 2.7 mrad about y). Held
to the initial equilibrium, the 500 N actuators saturate during and after the
move and the table never settles. Both therefore return a controller that
runs about the carriages' quasi-static path (:attr:`Controller.follows_path`):
:func:`~controllers.feedback.feedback_law` regulates it to
``quasi_static_path(scenario)`` unless given another reference.
"""

from __future__ import annotations

import control
import numpy as np

from isolator.analysis.linear import FORCE_INPUTS, LinearModel
from isolator.analysis.signal_names import labels, signals
from isolator.errors import OptimisationError, ParameterError
from isolator.scenario.arguments import check_public

from .designs import (
    MEASUREMENTS,
    SAMPLE_RATE,
    Controller,
    _measured_state,
    _scales,
    actuated,
    actuator_labels,
    positive,
)
from .hinf_output import import_slycot

__all__ = ["hinf", "lqr"]


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

    ``x`` is the deviation from the carriages' quasi-static path
    (``follows_path``): the weights hold the table to 0.1 mm and 0.1 mrad, and
    about the initial equilibrium ``K`` would fight the tilt of the carriages'
    weight (paper-table-3-2-active: its 500 N actuators saturate from the
    move on and stay saturated; the table never settles). About the path the
    LQR acts only on the motion the move excites, which settles within the
    passive run's band several times faster than passive, with forces well
    inside the limits and none left standing; the static tilt is left to
    the isolators (and the leveling). Washing the positions out instead
    (feedback on high-passed positions) leaves a slow creep at the washout's
    corner, and the path needs no tuning.

    Parameters
    ----------
    max_displacement, max_rotation, max_velocity, max_rate : float
        Acceptable table displacement [m], rotation [rad], velocity [m/s] and
        angular velocity [rad/s].
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
    _measured_state(lin, "lqr")
    a, b = actuated(lin)
    sx, su = _scales(lin, max_displacement, max_rotation, max_velocity, max_rate)
    gain_scaled, _, _ = control.lqr(a * sx[None, :] / sx[:, None], b * su[None, :] / sx[:, None],
                                    np.eye(sx.size), np.eye(su.size))
    gain = su[:, None] * np.asarray(gain_scaled, dtype=float) / sx[None, :]
    system = control.ss(np.zeros((0, 0)), np.zeros((0, 12)), np.zeros((b.shape[1], 0)), -gain,
                        inputs=list(MEASUREMENTS), outputs=signals(actuator_labels(lin.scenario)), name="lqr")
    return Controller("lqr", system, sample_rate,
                      f"LQR, Bryson weights: {max_displacement:.3g} m, {max_rotation:.3g} rad, "
                      f"{max_velocity:.3g} m/s, {max_rate:.3g} rad/s, max_force per actuator; "
                      "about the quasi-static path", follows_path=True)


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

    Parameters
    ----------
    lin : LinearModel
        The plant linearised at the design configuration, with ``[[actuators]]`` (their geometry, limits and
        lag are used).
    max_displacement, max_rotation, max_velocity, max_rate : float
        Acceptable table displacement [m], rotation [rad], velocity [m/s] and angular velocity [rad/s]: the
        scaling of the states.
    disturbance : float
        The wrench disturbance per axis [N, N m].
    noise : float
        Sensor noise as a fraction of each state's acceptable size [-].
    relax : float
        The controller's norm as a factor on the optimal one (>= 1).
    sample_rate : float
        The rate the controller runs at in the simulation [Hz].

    Returns
    -------
    Controller
        The continuous-time design and its sample rate.

    Raises
    ------
    ParameterError
        slycot is missing, or a weight is not a finite positive number.
    OptimisationError
        No controller achieves a finite norm.
    """
    slycot = import_slycot()
    _measured_state(lin, "hinf")
    a, b2 = actuated(lin)
    names = labels(lin.system.input_labels)
    bw = np.asarray(lin.system.B, dtype=float)[:, [names.index(n) for n in FORCE_INPUTS]]
    d = positive(disturbance, "disturbance")
    eps = positive(noise, "noise")
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
    factor = positive(relax, "relax")
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
                        outputs=signals(actuator_labels(lin.scenario)), name="hinf")
    return Controller("hinf", system, sample_rate,
                      f"H-infinity, gamma {float(gamma):.3g}: Bryson weights {max_displacement:.3g} m, "
                      f"{max_rotation:.3g} rad, {max_velocity:.3g} m/s, {max_rate:.3g} rad/s; "
                      f"disturbance {d:.3g} N, noise {eps:.3g}; about the quasi-static path", follows_path=True)


check_public(globals())
