"""Output-feedback designs from the scenario's sensors to its actuators, discrete at the sample rate.

Each design takes the :class:`~controllers.feedback.sensor_plant.SensorPlant` at one rest configuration
and returns the discrete ``(A, B, C, D)`` of a controller ``u_k = C x_k + D y_k``, ``x_{k+1} = A x_k +
B y_k`` (``y`` the sensors' readings minus their readings at rest, ``u`` the actuators' commands [N]):

* :func:`skyhook_design`: decentralised velocity feedback, each actuator pushing against the absolute velocity
  its collocated geophone (or band-limited integrated accelerometer) reads, through the second-order high-pass
  a real geophone loop needs (the sensor's drift, offset and tilt never reach the actuator). The gain is the
  one that gives the table's modes the most damping (root locus of the sampled loop, with the actuators' lag
  and the delay) unless given.
* :func:`lqg_design`: a Kalman filter (current estimator) from the sensors' noise and a process-noise model of
  the stage's reaction forces, with an LQR on the table's absolute velocities (not its positions: the
  carriages' weight tilts the table quasi-statically, and a position weight would push against every new
  equilibrium). Both on the sampled plant (``scipy.linalg.solve_discrete_are``).

Both in the plant's physical coordinates: neighbouring designs interpolate; H-infinity: :mod:`.hinf_output`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import control
import numpy as np
from scipy.linalg import solve_discrete_are

from isolator.errors import OptimisationError, ParameterError, ScenarioError
from isolator.scenario.arguments import check_public

from .designs import as_given, per_axis, positive
from .sensor_plant import DISTURBANCES, SensorPlant, loop_matrix

__all__ = [
    "DiscreteDesign",
    "NoiseModel",
    "disturbance_scale",
    "loop_damping",
    "lowest_mode_hz",
    "lqg_design",
    "noise_model",
    "refuse_held_air",
    "skyhook_design",
]

#: how close a sensor must sit to an actuator to count as collocated [m]
COLLOCATED = 1e-3
#: the smallest sensor noise the Kalman filter assumes, SI units (a noise-free sensor would make it singular)
NOISE_FLOOR = 1e-9


@dataclass(frozen=True)
class DiscreteDesign:
    """A discrete controller's matrices and what was chosen to design it.

    Attributes
    ----------
    A, B, C, D : ndarray
        ``x+ = A x + B y``, ``u = C x + D y`` (sensors in, commands [N] out, file order).
    settings : dict
        The design's settings as JSON values (gains, corners, weights).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    settings: dict[str, Any]

    @property
    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)``."""
        return self.A, self.B, self.C, self.D


def loop_damping(matrix: np.ndarray, sample_rate: float, held: int = 0) -> tuple[float, float]:
    """The sampled loop's spectral radius and its least-damped pole's damping ratio.

    Poles at ``z = 0`` (delays) and on the positive real axis (first-order lags, filters) count as fully
    damped; the rest are mapped to ``s = ln(z) f_s``. The ``held`` poles nearest ``z = 1`` are left out:
    a pneumatic table's held air (:attr:`SensorPlant.held_air`), which no controller reaches.

    Returns
    -------
    radius : float
    damping : float
        ``-Re(s) / |s|`` of the least-damped oscillatory pole (1 when there is none).
    """
    z = np.linalg.eigvals(matrix)
    if held:
        z = np.delete(z, np.argsort(np.abs(z - 1.0))[:held])
    radius = float(np.max(np.abs(z))) if z.size else 0.0
    oscillatory = z[(np.abs(z) > 1e-12) & (np.abs(z.imag) > 1e-9)]
    if oscillatory.size == 0:
        return radius, 1.0
    s = np.log(oscillatory) * sample_rate
    return radius, float(np.min(-s.real / np.abs(s)))


def _collocated(plant: SensorPlant) -> list[tuple[int, float]]:
    """For each actuator: the index of its collocated table velocity or acceleration sensor and the sign of
    its direction relative to the actuator's (parallel +1, antiparallel -1)."""
    scenario = plant.lin.scenario
    pairs = []
    for act in scenario.actuators:
        a_pos, a_dir = np.array(act.position), np.array(act.direction) / np.linalg.norm(act.direction)
        found = None
        for j, sensor in enumerate(scenario.sensors):
            if sensor.on != "table" or sensor.quantity == "displacement":
                continue
            cos = float(np.dot(a_dir, np.array(sensor.direction)))
            if np.linalg.norm(np.array(sensor.position) - a_pos) <= COLLOCATED and abs(cos) > 0.999:
                found = (j, math.copysign(1.0, cos))
                break
        if found is None:
            raise ScenarioError(f"sensors: skyhook needs a table velocity or acceleration sensor collocated with "
                                f"actuator '{act.name}' (same position within {COLLOCATED * 1e3:g} mm, along its "
                                "line); add one or use --method lqg or hinf")
        pairs.append(found)
    return pairs


def _filter(quantity: str, corner_hz: float, sample_rate: float) -> control.StateSpace:
    """The geophone loop's filter from the reading to the velocity the actuator acts on (Tustin, prewarped at
    the corner): a second-order Butterworth high-pass (velocity), the same times ``1/s`` (acceleration)."""
    w = 2 * math.pi * corner_hz
    den = [1.0, math.sqrt(2.0) * w, w * w]
    num = [1.0, 0.0, 0.0] if quantity == "velocity" else [1.0, 0.0]
    tf = control.tf(num, den)
    return control.ss(control.sample_system(tf, 1.0 / sample_rate, method="tustin", prewarp_frequency=w))


def lowest_mode_hz(plant: SensorPlant) -> float:
    """The table's lowest natural frequency [Hz]: its linear model's smallest eigenvalue magnitude, a
    pneumatic table's held air (poles at zero) left out."""
    return float(np.sort(np.abs(plant.lin.eigenvalues))[plant.held_air]) / (2 * math.pi)


def skyhook_design(plant: SensorPlant, sample_rate: float, delay: bool = False,
                   gain: float | Sequence[float] | None = None, highpass_hz: float | None = None) -> DiscreteDesign:
    """Decentralised skyhook damping from collocated geophones, discrete at ``sample_rate``.

    Every actuator commands ``u_i = -c s_i H(z) y_i``: ``y_i`` its collocated sensor's reading, ``s_i`` the
    sign between the two directions, ``H`` the Tustin form of the second-order Butterworth high-pass at
    ``highpass_hz`` (times ``1/s`` for an accelerometer).

    Parameters
    ----------
    plant : SensorPlant
        The sensor plant (:class:`SensorPlant`): commands to sensors with the actuators' lag, at the design
        position.
    sample_rate : float
        [Hz].
    delay : bool
        Design for one sample of computation delay (``u_k`` acting from ``t_{k+1}``).
    gain : float or sequence of 3 floats, optional
        ``c`` per actuator [N s/m], or one for the actuators along each world axis (x, y, z: an actuator's
        largest direction component). Default: one gain, on a logarithmic grid from 10 to 10^6 N s/m, that
        gives the sampled loop's least-damped pole the highest damping ratio (``isolator controller`` searches
        further: :mod:`controllers.feedback.output_tuning`).
    highpass_hz : float, optional
        The high-pass corner [Hz]; default a fifth of the table's lowest mode.

    Returns
    -------
    DiscreteDesign
        The controller's matrices ``(A, B, C, D)`` at ``sample_rate`` and the settings chosen.

    Raises
    ------
    ScenarioError
        An actuator has no collocated velocity or acceleration sensor.
    OptimisationError
        No gain on the grid gives a stable loop.
    """
    pairs = _collocated(plant)
    corner = lowest_mode_hz(plant) / 5 if highpass_hz is None else positive(highpass_hz, "highpass_hz")
    if corner >= sample_rate / 2:
        raise ParameterError(f"highpass_hz: the corner {corner:.4g} Hz must be below the Nyquist frequency "
                             f"{sample_rate / 2:.4g} Hz")
    sensors = plant.lin.scenario.sensors
    blocks = [_filter(sensors[j].quantity, corner, sample_rate) for j, _ in pairs]
    n_f, p, m = blocks[0].nstates, plant.n_sensors, plant.n_actuators
    a = np.zeros((n_f * m, n_f * m))
    b = np.zeros((n_f * m, p))
    c = np.zeros((m, n_f * m))
    d = np.zeros((m, p))
    for i, ((j, sign), f) in enumerate(zip(pairs, blocks, strict=True)):
        rows = slice(n_f * i, n_f * (i + 1))
        a[rows, rows] = np.asarray(f.A)
        b[rows, j] = np.asarray(f.B)[:, 0]
        c[i, rows] = -sign * np.asarray(f.C)[0]
        d[i, j] = -sign * float(np.asarray(f.D)[0, 0])
    sampled = plant.discrete(sample_rate, delay)

    axis = np.array([int(np.argmax(np.abs(act.direction))) for act in plant.lin.scenario.actuators])

    def damping(value: float | np.ndarray) -> tuple[float, float]:
        scale = np.broadcast_to(np.asarray(value, dtype=float), (m,))[:, None]
        return loop_damping(loop_matrix(sampled, (a, b, scale * c, scale * d)), sample_rate, plant.held_air)

    if gain is None:
        grid = np.logspace(1, 6, 61)
        scores = [(zeta if radius < 1 else -math.inf) for radius, zeta in map(damping, grid)]
        best = int(np.argmax(scores))
        if not math.isfinite(scores[best]):
            raise OptimisationError("skyhook: no gain from 10 to 1e6 N s/m gives a stable sampled loop (raise "
                                    "--sample-rate or the actuators' bandwidth)")
        gains = np.full(3, float(grid[best]))
    else:
        gains = per_axis(gain, "gain")
    scale = gains[axis]
    radius, zeta = damping(scale)
    return DiscreteDesign(a, b, scale[:, None] * c, scale[:, None] * d,
                          {"gain": as_given(gains), "highpass_hz": corner, "gain_chosen": gain is None,
                           "least_damping": zeta, "spectral_radius": radius})


def refuse_held_air(plant: SensorPlant, method: str) -> None:
    """A model-based design on a pneumatic table: its leveling groups' held air (poles at zero no actuator or
    sensor reaches) leaves the Riccati equations without a stabilising solution; a one-line refusal."""
    if plant.held_air:
        raise ParameterError(f"method: {method} cannot be designed on a pneumatic table (the air its leveling "
                             f"groups hold is {plant.held_air} pole(s) at zero that no actuator or sensor reaches); "
                             "use --method skyhook")


def disturbance_scale(plant: SensorPlant) -> np.ndarray:
    """RMS per sample of the process-noise model's wrench (6,) [N, N m]: the carriages' reaction at their
    largest acceleration, with the farthest isolator's horizontal distance as lever arm."""
    scenario = plant.lin.scenario
    force = 0.0
    for carriage in scenario.carriages:
        t = np.linspace(0.0, scenario.simulation.duration, 2001)
        acc = np.asarray(carriage.profile.evaluate(t)[2])
        force += carriage.mass * float(np.max(np.abs(acc)))
    force = max(force, 0.01 * scenario.table.mass)  # still carriages: 0.01 N per kg of table
    arm = max(float(np.hypot(*iso.position[:2])) for iso in scenario.isolators)
    return np.array([force] * 3 + [force * arm] * 3)


@dataclass(frozen=True)
class NoiseModel:
    """The disturbances an output-feedback design assumes (see :func:`noise_model`).

    Attributes
    ----------
    wrench : ndarray (6,)
        RMS per sample of the wrench at the mass centre [N, N m].
    walk : float
        RMS per sample of the random walk of each position state [m, rad].
    noise : ndarray (sensors,)
        Each sensor's noise RMS assumed [SI units].
    washout_hz : float
        The slowest rate of the filter's estimate [Hz].
    gain : ndarray (states, sensors)
        The Kalman filter's measurement-update gain ``M`` (current estimator).
    """

    wrench: np.ndarray
    walk: float
    noise: np.ndarray
    washout_hz: float
    gain: np.ndarray


def noise_model(plant: SensorPlant, sampled: control.StateSpace, noise_floor: float = NOISE_FLOOR,
                washout_hz: float | None = None) -> NoiseModel:
    """The process and measurement noise of the output-feedback designs, and the Kalman filter they give.

    Process noise: a white wrench at the mass centre whose RMS is the carriages' largest reaction force
    (:func:`disturbance_scale`), held over each sample, and a random walk of the six position states sized
    so that the filter forgets a position estimate at ``washout_hz`` [Hz] or faster (geophones do not see a
    static position: without it the estimate integrates their noise with a pole at ``z = 1``). The walk is
    found by scaling: the slowest filter pole's rate grows in proportion to it. Measurement noise: each
    sensor's noise per sample at the design's rate (``Sensor.noise_rms``), at least ``noise_floor``.

    Parameters
    ----------
    plant : SensorPlant
    sampled : control.StateSpace
        ``plant.discrete(...)`` at the design's rate and delay.
    noise_floor : float
        [SI units].
    washout_hz : float, optional
        Default a fifth of the table's lowest mode.
    """
    ad, cy = np.asarray(sampled.A), np.asarray(sampled.C)
    bw = np.asarray(sampled.B)[:, plant.n_actuators:]
    n = ad.shape[0]
    wrench = disturbance_scale(plant)
    sw = np.zeros(len(DISTURBANCES))
    sw[6:] = wrench  # the force and torque inputs; the floor is left to the measurement update
    noise = np.array([max(s.noise_rms(1.0 / float(sampled.dt)), noise_floor) for s in plant.lin.scenario.sensors])
    rn = np.diag(noise**2)
    qn = bw @ np.diag(sw**2) @ bw.T
    qn += 1e-12 * np.trace(qn) / n * np.eye(n)  # every state slightly excited: a well-posed filter
    corner = lowest_mode_hz(plant) / 5 if washout_hz is None else positive(washout_hz, "washout_hz")
    rate = 2 * math.pi * corner / float(1.0 / sampled.dt)

    def gain(walk: float) -> tuple[np.ndarray, float]:
        qw = qn.copy()
        qw[np.arange(6), np.arange(6)] += walk**2
        pf = solve_discrete_are(ad.T, cy.T, qw, rn)
        mk = pf @ cy.T @ np.linalg.inv(cy @ pf @ cy.T + rn)
        poles = np.linalg.eigvals(ad - ad @ mk @ cy)
        return mk, float(-np.max(np.log(np.abs(poles[np.abs(poles) > 1e-12]))))

    walk = 1e-9
    mk, slowest = gain(walk)
    for _ in range(3):
        if slowest >= 0.98 * rate:
            break
        walk *= rate / max(slowest, 1e-12)
        mk, slowest = gain(walk)
    return NoiseModel(wrench, walk, noise, corner, mk)


def lqg_design(plant: SensorPlant, sample_rate: float, delay: bool = False,
               max_velocity: float | Sequence[float] = 1e-2, max_rate: float | Sequence[float] = 1e-2,
               noise_floor: float = NOISE_FLOOR, washout_hz: float | None = None) -> DiscreteDesign:
    """LQG from the sensors: Kalman filter (current estimator) and LQR on the sampled plant.

    Cost ``sum (v / max_velocity)^2 + (w / max_rate)^2 + (u_i / max_force_i)^2`` over the table's
    absolute velocity ``v`` and angular velocity ``w`` and the commands. Process noise: a white wrench at
    the mass centre whose RMS is the carriages' largest reaction force (and that times the farthest
    isolator's horizontal distance as moment), held over each sample, and a random walk of the table's position whose
    size makes the filter forget a position estimate no faster than ``washout_hz`` (geophones do not
    see a static position: without it the estimate integrates their noise and drift with a pole at
    ``z = 1``, and the regulator acts on that); measurement noise: each sensor's ``noise`` (at least
    ``noise_floor``).

    Parameters
    ----------
    plant : SensorPlant
        The sensor plant (:class:`SensorPlant`): commands to sensors with the actuators' lag, at the design
        position.
    sample_rate : float
        [Hz].
    delay : bool
        Design for one sample of computation delay: the plant's delay states are part of the estimate.
    max_velocity, max_rate : float or sequence of 3 floats
        Acceptable table velocity [m/s] and angular velocity [rad/s] (Bryson's rule), one for all three axes or
        one per world axis (x, y, z). ``isolator controller`` chooses them per axis when not given
        (:mod:`controllers.feedback.output_tuning`).
    noise_floor : float
        Smallest sensor noise RMS assumed [SI units].
    washout_hz : float, optional
        The slowest rate [Hz] of the filter's estimate (default a fifth of the table's lowest mode).

    Returns
    -------
    DiscreteDesign
        The controller's matrices ``(A, B, C, D)`` at ``sample_rate`` and the settings chosen.

    Raises
    ------
    OptimisationError
        A Riccati equation has no stabilising solution.
    """
    refuse_held_air(plant, "lqg")
    v_max, w_max = per_axis(max_velocity, "max_velocity"), per_axis(max_rate, "max_rate")
    floor = positive(noise_floor, "noise_floor")
    sampled = plant.discrete(sample_rate, delay)
    m = plant.n_actuators
    ad, b = np.asarray(sampled.A), np.asarray(sampled.B)
    cy, d = np.asarray(sampled.C), np.asarray(sampled.D)
    bu, du = b[:, :m], d[:, :m]
    n = ad.shape[0]
    cz = np.zeros((6, n))
    cz[np.arange(6), 6 + np.arange(6)] = 1.0 / np.concatenate([v_max, w_max])
    limits = np.array([a.max_force for a in plant.lin.scenario.actuators])
    q = cz.T @ cz
    r = np.diag(1.0 / limits**2)
    try:
        s = solve_discrete_are(ad, bu, q, r)
        k = np.linalg.solve(r + bu.T @ s @ bu, bu.T @ s @ ad)
        model = noise_model(plant, sampled, floor, washout_hz)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise OptimisationError(f"lqg: no stabilising Riccati solution for these weights ({exc})") from None
    mk, wrench, walk, corner = model.gain, model.wrench, model.walk, model.washout_hz
    # current estimator: xh = xb + M (y - C xb - D u), u = -K xh, xb+ = A xh + B u
    eye = np.eye(n)
    w = np.linalg.inv(np.eye(m) - k @ mk @ du)
    cc = -w @ k @ (eye - mk @ cy)
    dc = -w @ k @ mk
    ac = ad @ (eye - mk @ cy) + (bu - ad @ mk @ du) @ cc
    bcm = ad @ mk + (bu - ad @ mk @ du) @ dc
    radius, zeta = loop_damping(loop_matrix(sampled, (ac, bcm, cc, dc)), sample_rate)
    return DiscreteDesign(ac, bcm, cc, dc, {"max_velocity": as_given(v_max), "max_rate": as_given(w_max),
                                            "noise_floor": floor,
                                            "process_force": float(wrench[0]), "washout_hz": corner,
                                            "position_walk": walk, "least_damping": zeta,
                                            "spectral_radius": radius})


check_public(globals())
