"""H-infinity output feedback from the sensors, designed on the sampled plant (needs slycot).

The generalised plant is the sampled :class:`~controllers.feedback.sensor_plant.SensorPlant` (actuators'
lag and any computation delay included) with

* exogenous inputs ``w``: a wrench at the mass centre (the carriages' largest reaction force, as in
  :func:`~controllers.feedback.output_designs.lqg_design`) and each sensor's noise (its ``noise``, at
  least the noise floor), both normalised to one;
* performance outputs ``z``: the table's absolute velocity and angular velocity over ``max_velocity`` and
  ``max_rate``, each command over its actuator's ``max_force``;
* measurements ``y``: the sensors' readings with their noise; controls ``u``: the commands.

The discrete problem is solved exactly in the ``w``-plane: the bilinear map ``z = (1 + s T/2) / (1 - s T/2)``
takes the sampled plant to a continuous one with the same H-infinity norm for every controller, python-control's
``hinfsyn`` (slycot) finds the optimal norm ``gamma`` there, slycot ``sb10ad`` the central controller at
``relax * gamma`` (the optimal one has poles far beyond any sample rate), and Tustin's map brings it back.
A direct feedthrough from the commands to the readings (accelerometers, or the ``w``-plane's own) is removed
before the synthesis and restored after it (loop shifting).

Its states are the synthesis's, not the plant's: two designs at neighbouring carriage positions have no
common coordinates to interpolate, so an H-infinity design is not gain-scheduled.
"""

from __future__ import annotations

import math

import control
import numpy as np
from scipy.signal import cont2discrete

from isolator.errors import OptimisationError, ParameterError
from isolator.scenario.arguments import check_public

from .output_designs import NOISE_FLOOR, DiscreteDesign, disturbance_scale, loop_damping, positive
from .sensor_plant import SensorPlant, loop_matrix

__all__ = ["hinf_design"]


def _to_w_plane(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray, period: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The continuous system whose Tustin discretisation at ``period`` [s] is ``(a, b, c, d)``."""
    inv = np.linalg.inv(a + np.eye(a.shape[0]))
    return (2.0 / period) * (np.eye(a.shape[0]) - 2.0 * inv), (2.0 / period) * inv @ b, 2.0 * c @ inv, d - c @ inv @ b


def hinf_design(plant: SensorPlant, sample_rate: float, delay: bool = False, max_velocity: float = 1e-2,
                max_rate: float = 1e-2, noise_floor: float = NOISE_FLOOR, relax: float = 1.5) -> DiscreteDesign:
    """H-infinity output feedback from the sensors to the actuators, discrete at ``sample_rate``.

    Parameters
    ----------
    plant : SensorPlant
    sample_rate : float
        [Hz].
    delay : bool
        Design for one sample of computation delay.
    max_velocity, max_rate : float
        The table's acceptable velocity [m/s] and angular velocity [rad/s].
    noise_floor : float
        Smallest sensor noise RMS assumed [SI units].
    relax : float
        The controller's norm as a factor on the optimal one (>= 1).

    Raises
    ------
    ParameterError
        slycot is missing, or a setting is out of range.
    OptimisationError
        No controller achieves a finite norm.
    """
    try:
        import slycot
    except ImportError:
        raise ParameterError('controller: hinf needs slycot: pip install ".[hinf]" (the extra "hinf"; or pip '
                             "install slycot)") from None
    v_max, w_max = positive(max_velocity, "max_velocity"), positive(max_rate, "max_rate")
    floor, factor = positive(noise_floor, "noise_floor"), positive(relax, "relax")
    if factor < 1:
        raise ParameterError(f"relax: must be >= 1 (a factor on the optimal norm), got {relax}")
    sampled = plant.discrete(sample_rate, delay)
    m, p = plant.n_actuators, plant.n_sensors
    ad, b = np.asarray(sampled.A), np.asarray(sampled.B)
    cy, d = np.asarray(sampled.C), np.asarray(sampled.D)
    n = ad.shape[0]
    limits = np.array([act.max_force for act in plant.lin.scenario.actuators])
    noise = np.array([max(s.noise, floor) for s in plant.lin.scenario.sensors])
    wrench = disturbance_scale(plant)
    # w = (wrench / scale (6), noise / level (p)); z = (velocities / max (6), u / max_force (m)); y; u
    b1 = np.hstack([b[:, m + 6:] * wrench[None, :], np.zeros((n, p))])
    c1 = np.zeros((6 + m, n))
    c1[np.arange(6), 6 + np.arange(6)] = 1.0 / np.array([v_max] * 3 + [w_max] * 3)
    d12 = np.vstack([np.zeros((6, m)), np.diag(1.0 / limits)])
    d21 = np.hstack([d[:, m + 6:] * wrench[None, :], np.diag(noise)])
    big_a, big_b, big_c, big_d = _to_w_plane(
        ad, np.hstack([b1, b[:, :m]]), np.vstack([c1, cy]),
        np.block([[np.zeros((6 + m, 6 + p)), d12], [d21, d[:, :m]]]), 1.0 / sample_rate)
    d22 = big_d[6 + m:, 6 + p:].copy()
    big_d[6 + m:, 6 + p:] = 0.0  # loop shifting: synthesise for y - D22 u
    generalised = control.ss(big_a, big_b, big_c, big_d)
    try:
        _, _, optimal, _ = control.hinfsyn(generalised, p, m)
        gamma = factor * float(optimal)
        out = slycot.sb10ad(n, 6 + p + m, 6 + m + p, m, p, gamma, big_a, big_b, big_c, big_d, job=4)
    except Exception as exc:  # slycot reports failures as its own exception types
        raise OptimisationError(f"hinf: no H-infinity controller for these weights ({exc})") from None
    ak, bk, ck, dk = (np.asarray(x, dtype=float) for x in out[1:5])
    f = np.linalg.inv(np.eye(m) + dk @ d22)
    ak, bk, ck, dk = ak - bk @ d22 @ f @ ck, bk - bk @ d22 @ f @ dk, f @ ck, f @ dk
    a_c, b_c, c_c, d_c, _ = cont2discrete((ak, bk, ck, dk), 1.0 / sample_rate, method="bilinear")
    radius, zeta = loop_damping(loop_matrix(sampled, (a_c, b_c, c_c, d_c)), sample_rate)
    if not math.isfinite(radius) or radius >= 1.0:
        raise OptimisationError(f"hinf: the synthesised loop is not stable at the sample rate (spectral radius "
                                f"{radius:.6g}); try a larger relax or lower weights")
    return DiscreteDesign(a_c, b_c, c_c, d_c, {"gamma": gamma, "optimal_gamma": float(optimal), "relax": factor,
                                               "max_velocity": v_max, "max_rate": w_max, "noise_floor": floor,
                                               "process_force": float(wrench[0]), "least_damping": zeta,
                                               "spectral_radius": radius})


check_public(globals())
