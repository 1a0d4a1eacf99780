"""The loops an exported controller closes, in the frequency domain and under sensor noise.

For a :class:`~isolator.simulation.discrete_controller.DiscreteController` around the continuous
:class:`~controllers.feedback.sensor_plant.SensorPlant` (the hybrid loop as it runs: readings sampled,
commands held), below the Nyquist frequency the loop's response is that of the continuous plant ``P(jw)``
with the controller's ``K(e^{jwT})`` times the zero-order hold's ``(1 - e^{-jwT}) / (jwT)`` (and ``e^{-jwT}``
with a computation delay); the aliases above Nyquist are left out. With ``u = K y`` (the sign inside ``K``)
the sensors' output sensitivity is ``S = (I - P_yu K)^-1``, the complementary sensitivity ``T = I - S``, and
the floor-to-sensor transmissibility ``S P_yw``.

The table's motion caused by sensor noise is exact for the sampled loop: white noise of each sensor's
``noise`` RMS per sample drives the discrete loop, whose stationary covariance solves a discrete Lyapunov
equation (solved by doubling); the RMS of the six table signals and of each actuator's command follow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from controllers.feedback.loop_margins import DiscreteResponse
from controllers.feedback.sensor_plant import SensorPlant, loop_matrix
from isolator.analysis.frequency_response import state_space_response
from isolator.analysis.signal_names import labels
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import SIGNALS
from isolator.simulation.discrete_controller import DiscreteController

__all__ = ["LoopResponse", "NoiseMotion", "loop_response", "noise_motion"]


@dataclass(frozen=True)
class LoopResponse:
    """The hybrid loop's frequency responses at the sensors.

    Attributes
    ----------
    frequency_hz : ndarray (nf,)
        Below Nyquist [Hz].
    sensitivity, complementary : ndarray (nf,)
        Largest singular value of ``S`` and of ``T`` at each frequency.
    transmissibility : ndarray (nf, sensors)
        Each sensor's reading per the floor's motion along the sensor's direction in the same quantity,
        closed loop (dimensionless).
    passive : ndarray (nf, sensors)
        The same without the controller.
    """

    frequency_hz: np.ndarray
    sensitivity: np.ndarray
    complementary: np.ndarray
    transmissibility: np.ndarray
    passive: np.ndarray


def loop_response(plant: SensorPlant, controller: DiscreteController, frequency_hz: np.ndarray,
                  q: np.ndarray | None = None) -> LoopResponse:
    """The loop's sensitivities and floor-to-sensor transmissibility at ``frequency_hz`` [Hz] (below Nyquist).

    Parameters
    ----------
    plant : SensorPlant
        At the configuration to evaluate.
    controller : DiscreteController
    q : ndarray, optional
        The carriages' positions that schedule the controller [m] (default: the plant's).
    """
    f = np.asarray(frequency_hz, dtype=float)
    period = 1.0 / controller.sample_rate
    w = 2 * math.pi * f
    zs = np.exp(1j * w * period)
    ctrl = controller.matrices(plant.lin.positions if q is None else q)
    k = DiscreteResponse(*ctrl)(zs)
    hold = np.where(w > 0, (1 - np.exp(-1j * w * period)) / np.where(w > 0, 1j * w * period, 1.0), 1.0)
    if controller.delay:
        hold = hold * np.exp(-1j * w * period)
    m = plant.n_actuators
    actuated = state_space_response(plant.system, f, labels(plant.system.input_labels)[:m])
    sensors = plant.lin.scenario.sensors
    # the floor's path to the sensors, exact in each sensor's quantity (an accelerometer's improper term too)
    floor_path = plant.lin.sensor_response(f, [f"ground:{axis}" for axis in ("x", "y", "z")])
    p = len(sensors)
    sens, comp = np.empty(f.size), np.empty(f.size)
    trans, passive = np.empty((f.size, p)), np.empty((f.size, p))
    for i, wi in enumerate(w):
        s = 1j * wi
        pu, pw = actuated[i], floor_path[i]
        loop = pu @ (hold[i] * k[i])
        so = np.linalg.inv(np.eye(p) - loop)
        sens[i] = np.linalg.norm(so, 2)
        comp[i] = np.linalg.norm(np.eye(p) - so, 2)
        closed = so @ pw
        for j, sensor in enumerate(sensors):
            direction = np.asarray(sensor.direction, dtype=float)
            floor = s ** sensor.order if wi > 0 or sensor.order == 0 else 0.0  # floor motion in the same quantity
            scale = 1.0 / floor if floor != 0 else 0.0
            trans[i, j] = abs(closed[j] @ direction * scale)
            passive[i, j] = abs(pw[j] @ direction * scale)
    return LoopResponse(f, sens, comp, trans, passive)


@dataclass(frozen=True)
class NoiseMotion:
    """The stationary motion of the table and the commands that sensor noise alone causes.

    Attributes
    ----------
    table_rms : dict
        RMS of each of the six table signals [m, rad].
    force_rms : ndarray (actuators,)
        RMS of each actuator's command [N].
    """

    table_rms: dict[str, float]
    force_rms: np.ndarray


def _stationary_covariance(a: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``X = sum_k A^k Q A^k^T`` (``X = A X A^T + Q``) by doubling (Smith's method): the direct and bilinear
    Lyapunov solvers lose a loop whose states span metres to newtons with poles near ``z = 1``."""
    x, power = q.copy(), a.copy()
    for _ in range(64):
        x = x + power @ x @ power.T
        power = power @ power
        if np.max(np.abs(power)) < 1e-18:
            break
    return x


def noise_motion(plant: SensorPlant, controller: DiscreteController, q: np.ndarray | None = None) -> NoiseMotion:
    """The table's RMS motion and the commands' RMS from the sensors' white noise (each ``noise`` RMS per
    sample) through the sampled loop at the plant's configuration.

    Raises
    ------
    ValueError
        The loop is unstable (no stationary motion).
    """
    ctrl = controller.matrices(plant.lin.positions if q is None else q)
    sampled = plant.discrete(controller.sample_rate, controller.delay)
    big = loop_matrix(sampled, ctrl)
    if np.max(np.abs(np.linalg.eigvals(big))) >= 1:
        raise ValueError("noise_motion: the sampled loop is unstable; it has no stationary motion")
    _, bc, cc, dc = ctrl
    m = plant.n_actuators
    dp = np.asarray(sampled.D)[:, :m]
    bp, cp = np.asarray(sampled.B)[:, :m], np.asarray(sampled.C)
    e = np.linalg.inv(np.eye(m) - dc @ dp)
    # the noise n enters the readings: u = E (Dc (Cp x + Dp u + n) + Cc xc) -> u = ... + E Dc n
    bn = np.vstack([bp @ e @ dc, bc + bc @ dp @ e @ dc])
    sigma = np.diag([s.noise_rms(controller.sample_rate) ** 2 for s in plant.lin.scenario.sensors])
    cov = _stationary_covariance(big, bn @ sigma @ bn.T)
    outputs = labels(plant.lin.system.output_labels)
    rows = np.asarray(plant.lin.system.C)[[outputs.index(s) for s in SIGNALS]]
    table = np.hstack([rows, np.zeros((6, big.shape[0] - rows.shape[1]))])
    table_rms = {s: float(math.sqrt(max(v, 0.0))) for s, v in zip(SIGNALS, np.diag(table @ cov @ table.T),
                                                                 strict=True)}
    cu = np.hstack([e @ dc @ cp, e @ cc])
    du = e @ dc
    force = np.sqrt(np.maximum(np.diag(cu @ cov @ cu.T + du @ sigma @ du.T), 0.0))
    return NoiseMotion(table_rms, force)


check_public(globals())
