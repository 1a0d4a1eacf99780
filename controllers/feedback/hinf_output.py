"""H-infinity output feedback from the sensors, designed on the sampled plant (needs slycot).

The generalised plant is the sampled :class:`~controllers.feedback.sensor_plant.SensorPlant` (actuators'
lag and any computation delay included) with

* exogenous inputs ``w``: a wrench at the mass centre (the carriages' largest reaction force) and the
  random walk of the table's position that washes the position estimate out, as in
  :func:`~controllers.feedback.output_designs.noise_model`, and each sensor's noise (``noise_weight``),
  all normalised to one;
* performance outputs ``z``: the table's absolute velocity and angular velocity over ``max_velocity`` and
  ``max_rate``, each command over its actuator's ``max_force``;
* measurements ``y``: the sensors' readings with their noise; controls ``u``: the commands.

The discrete problem is solved exactly in the ``w``-plane: the bilinear map ``z = (1 + s T/2) / (1 - s T/2)``
takes the sampled plant to a continuous one with the same H-infinity norm for every controller, slycot
``sb10ad`` (the routine behind python-control's ``hinfsyn``) decides whether a norm ``gamma`` is achievable
there (the optimal one by bisection to 1 %), gives the central controller at ``relax * gamma`` (the optimal
one has poles far beyond any sample rate), and Tustin's map brings it back.
A direct feedthrough from the commands to the readings (accelerometers, or the ``w``-plane's own) is removed
before the synthesis and restored after it (loop shifting).

Its states are the synthesis's, not the plant's: two designs at neighbouring carriage positions have no
common coordinates to interpolate, so an H-infinity design is not gain-scheduled.
"""

from __future__ import annotations

import math
from types import ModuleType

import numpy as np
from scipy.linalg import matrix_balance
from scipy.signal import cont2discrete

from isolator.errors import OptimisationError, ParameterError
from isolator.scenario.arguments import check_public

from .designs import positive
from .output_designs import (
    NOISE_FLOOR,
    DiscreteDesign,
    loop_damping,
    lowest_mode_hz,
    noise_model,
    refuse_held_air,
)
from .sensor_plant import SensorPlant, loop_matrix

__all__ = ["hinf_design", "import_slycot"]

#: slycot's bound on the real part of the w-plane loop's poles [1/s]: the loop is judged afterwards, sampled
#: (a pole at -1e-9 from a near-uncontrollable static position must not fail the search)
ACTOL = 1e-6


def import_slycot() -> ModuleType:
    """slycot, or a :class:`ParameterError` saying how to install it (the H-infinity designs need it)."""
    try:
        import slycot
    except ImportError:
        raise ParameterError('controller: hinf needs slycot: pip install ".[hinf]" (the extra "hinf"; or pip '
                             "install slycot)") from None
    return slycot


def _to_w_plane(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray, period: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The continuous system whose Tustin discretisation at ``period`` [s] is ``(a, b, c, d)``."""
    inv = np.linalg.inv(a + np.eye(a.shape[0]))
    return (2.0 / period) * (np.eye(a.shape[0]) - 2.0 * inv), (2.0 / period) * inv @ b, 2.0 * c @ inv, d - c @ inv @ b


def hinf_design(plant: SensorPlant, sample_rate: float, delay: bool = False, max_velocity: float = 1e-2,
                max_rate: float = 1e-2, noise_floor: float = NOISE_FLOOR, noise_weight: float = 0.1,
                relax: float = 1.5) -> DiscreteDesign:
    """H-infinity output feedback from the sensors to the actuators, discrete at ``sample_rate``.

    Parameters
    ----------
    plant : SensorPlant
        The sensor plant (:class:`SensorPlant`): commands to sensors with the actuators' lag, at the design
        position.
    sample_rate : float
        [Hz].
    delay : bool
        Design for one sample of computation delay.
    max_velocity, max_rate : float
        The table's acceptable velocity [m/s] and angular velocity [rad/s].
    noise_floor : float
        Smallest sensor noise RMS assumed [SI units].
    noise_weight : float
        The sensors' noise in the synthesis, at least this fraction of the reading that ``max_velocity`` gives
        at the table's lowest mode (the true noise of a geophone, 1e-8 m/s, against a 1e-2 m/s acceptable
        velocity makes the synthesis singular); the larger of it and the sensor's ``noise``.
    relax : float
        The controller's norm as a factor on the optimal one (>= 1).

    Returns
    -------
    DiscreteDesign
        The controller's matrices ``(A, B, C, D)`` at ``sample_rate`` and the settings chosen.

    Raises
    ------
    ParameterError
        slycot is missing, or a setting is out of range.
    OptimisationError
        No controller achieves a finite norm.
    """
    slycot = import_slycot()
    refuse_held_air(plant, "hinf")
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
    model = noise_model(plant, sampled, floor)
    # the sensors' noise as a design weight: a fraction of the reading an acceptable velocity gives
    w_low = 2 * math.pi * lowest_mode_hz(plant)
    typical = np.array([v_max * w_low ** (s.order - 1) for s in plant.lin.scenario.sensors])
    noise = np.maximum(model.noise, positive(noise_weight, "noise_weight") * typical)
    # w = (wrench (6), position walk (6), noise (p)), each normalised; z = (velocities, commands) normalised
    walk = np.zeros((n, 6))
    walk[np.arange(6), np.arange(6)] = model.walk
    nw = 12 + p
    # normalised signals: readings over their noise (y_s = y / noise), commands over their limit (u = max u_s)
    b1 = np.hstack([b[:, m + 6:] * model.wrench[None, :], walk, np.zeros((n, p))])
    b2 = b[:, :m] * limits[None, :]
    c1 = np.zeros((6 + m, n))
    c1[np.arange(6), 6 + np.arange(6)] = 1.0 / np.array([v_max] * 3 + [w_max] * 3)
    c2 = cy / noise[:, None]
    d12 = np.vstack([np.zeros((6, m)), np.eye(m)])
    d21 = np.hstack([d[:, m + 6:] * model.wrench[None, :] / noise[:, None], np.zeros((p, 6)), np.eye(p)])
    d22s = d[:, :m] * limits[None, :] / noise[:, None]
    big_a, big_b, big_c, big_d = _to_w_plane(ad, np.hstack([b1, b2]), np.vstack([c1, c2]),
                                             np.block([[np.zeros((6 + m, nw)), d12], [d21, d22s]]), 1.0 / sample_rate)
    scale = matrix_balance(big_a, permute=False, separate=True)[1][0]  # states balanced: D^-1 A D
    big_a, big_b, big_c = big_a * scale[None, :] / scale[:, None], big_b / scale[:, None], big_c * scale[None, :]
    d22 = big_d[6 + m:, nw:].copy()
    big_d[6 + m:, nw:] = 0.0  # loop shifting: synthesise for y - D22 u

    def synthesise(gamma: float) -> tuple | None:
        try:
            return slycot.sb10ad(n, nw + m, 6 + m + p, m, p, gamma, big_a, big_b, big_c, big_d, job=4, actol=ACTOL)
        except Exception:  # slycot reports failures as its own exception types
            return None

    # the optimal norm by bisection in log gamma (slycot's own search can stall on a plant this stiff)
    high = 1.0
    while synthesise(high) is None:
        high *= 10.0
        if high > 1e12:
            raise OptimisationError("hinf: no H-infinity controller for these weights (none up to a norm of 1e12)")
    low = high / 10.0
    for _ in range(14):
        mid = math.sqrt(low * high)
        low, high = (low, mid) if synthesise(mid) is not None else (mid, high)
    optimal = high
    gamma = factor * optimal
    out = synthesise(gamma)
    for _ in range(4):  # slycot's Riccati solutions are fragile on this stiff plant: a little more norm
        if out is not None:
            break
        gamma *= 1.1
        out = synthesise(gamma)
    if out is None:
        raise OptimisationError(f"hinf: no controller at {factor:g} times the optimal norm {optimal:.4g}")
    ak, bk, ck, dk = (np.asarray(x, dtype=float) for x in out[1:5])
    f = np.linalg.inv(np.eye(m) + dk @ d22)
    ak, bk, ck, dk = ak - bk @ d22 @ f @ ck, bk - bk @ d22 @ f @ dk, f @ ck, f @ dk
    # back to SI: u = max u_s, y_s = y / noise
    bk, ck, dk = bk / noise[None, :], limits[:, None] * ck, limits[:, None] * dk / noise[None, :]
    a_c, b_c, c_c, d_c, _ = cont2discrete((ak, bk, ck, dk), 1.0 / sample_rate, method="bilinear")
    radius, zeta = loop_damping(loop_matrix(sampled, (a_c, b_c, c_c, d_c)), sample_rate)
    if not math.isfinite(radius) or radius >= 1.0:
        raise OptimisationError(f"hinf: the synthesised loop is not stable at the sample rate (spectral radius "
                                f"{radius:.6g}); try a larger relax or lower weights")
    settings: dict[str, float | str | bool] = {
        "gamma": gamma, "optimal_gamma": optimal, "relax": factor, "max_velocity": v_max, "max_rate": w_max,
        "noise_floor": floor, "noise_weight": float(noise_weight), "process_force": float(model.wrench[0]),
        "position_walk": model.walk, "least_damping": zeta, "spectral_radius": radius}
    return DiscreteDesign(a_c, b_c, c_c, d_c, settings)


check_public(globals())
