"""How each random source reaches the points: the passive table, or the sampled loop of an exported controller
in the frequency domain (``docs/scenario-format.md``, "Error budget").

At each frequency ``f < fs/2``, with ``z = exp(j 2 pi f / fs)``, the zero-order hold
``H0 = (1 - z^-1) / (j 2 pi f / fs)``, each actuator's lag ``L`` and the controller's ``K(z)`` (times ``z^-1``
with the design's delay), the commands ``v`` satisfy ``v = K (M_sa v + P_sw w + n)``, so

``T_w = P_pw + M_pa (I - K M_sa)^-1 K P_sw`` (a physical source ``w``: floor, force, actuator noise) and
``T_n = M_pa (I - K M_sa)^-1 K`` (a sensor's noise ``n``),

with ``P`` the continuous plant's responses (``p`` the points, ``s`` the sensors in their quantities),
``M_pa = P_pa L H0`` and ``M_sa = P_sa L H0`` (an actuator without lag read by an accelerometer at once: the
direct part ``D_sa`` seen one sample late, ``(P_sa - D_sa) H0 + D_sa z^-1``, the readings' left limit).
Aliasing is neglected. The loop's stability and its resonances come from the exactly sampled loop
(:func:`isolator.analysis.sampling.sample_held`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

import numpy as np

from isolator.analysis.linear import LinearModel
from isolator.analysis.sampling import closed_loop_matrix, sample_held
from isolator.errors import ParameterError, UnstableClosedLoopError
from isolator.scenario.definitions import Scenario

from .sources import Source

__all__ = ["SampledController", "closed_loop_poles", "source_responses"]


class SampledController(Protocol):
    """What the budget reads of an exported controller
    (:class:`~isolator.simulation.discrete_controller.DiscreteController`)."""

    @property
    def sample_rate(self) -> float: ...  # [Hz]

    @property
    def delay(self) -> bool: ...  # one sample of computation delay

    @property
    def method(self) -> str: ...  # the design's name

    def matrices(self, q: Sequence[float] | np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]: ...

    def check_names(self, scenario: Scenario) -> None: ...


def _indices(lin: LinearModel) -> tuple[list[int], list[int]]:
    """The linear model's input columns of the actuators and output rows of the sensors, in file order."""
    inputs, outputs = lin.input_names, lin.output_names
    return ([inputs.index(f"actuator:{a.name}") for a in lin.scenario.actuators],
            [outputs.index(f"s:{s.name}") for s in lin.scenario.sensors])


def _command_plant(lin: LinearModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, C, D)`` from the actuators' commands [N] to the sensors' readings, each lagged actuator's
    force a state (what the sampled loop's stability and resonances are computed on)."""
    iu, ys = _indices(lin)
    sys = lin.system
    a, b = np.asarray(sys.A, dtype=float), np.asarray(sys.B, dtype=float)[:, iu]
    c, d = np.asarray(sys.C, dtype=float)[ys], np.asarray(sys.D, dtype=float)[np.ix_(ys, iu)]
    acts = lin.scenario.actuators
    lagged = [k for k, act in enumerate(acts) if act.bandwidth is not None]
    n, nl, m = a.shape[0], len(lagged), len(acts)
    omega = np.array([2 * math.pi * acts[k].bandwidth for k in lagged])  # type: ignore[operator]
    a_full = np.zeros((n + nl, n + nl))
    a_full[:n, :n], a_full[:n, n:], a_full[n:, n:] = a, b[:, lagged], -np.diag(omega)
    b_full = np.zeros((n + nl, m))
    direct = [k for k in range(m) if k not in lagged]
    b_full[:n, direct] = b[:, direct]
    b_full[n + np.arange(nl), lagged] = omega
    c_full = np.hstack([c, d[:, lagged]])  # an accelerometer reads a lagged force through its state
    d_full = np.zeros_like(d)
    d_full[:, direct] = d[:, direct]
    return a_full, b_full, c_full, d_full


def closed_loop_poles(lin: LinearModel, controller: SampledController) -> np.ndarray:
    """The exactly sampled loop's poles as continuous ones, ``s = fs ln z`` [1/s].

    Raises
    ------
    UnstableClosedLoopError
        A pole outside the unit circle (naming the largest and its frequency).
    """
    fs = float(controller.sample_rate)
    plant = sample_held(_command_plant(lin), len(lin.scenario.actuators), fs, bool(controller.delay))
    kd = tuple(np.asarray(x, dtype=float) for x in controller.matrices(lin.positions))
    m = len(lin.scenario.actuators)
    z = np.linalg.eigvals(closed_loop_matrix((plant[0], plant[1][:, :m], plant[2], plant[3][:, :m]), kd))
    worst = int(np.argmax(np.abs(z))) if z.size else -1
    if z.size and abs(z[worst]) > 1.0 + 1e-9:
        f = abs(np.angle(z[worst])) * fs / (2 * math.pi)
        raise UnstableClosedLoopError(
            f"controller: the sampled loop is unstable at this rest configuration (a pole at |z| = "
            f"{abs(z[worst]):.6g}, {f:.4g} Hz): no random motion has a finite RMS")
    z = z[np.abs(z) > 1e-12]
    return np.log(z) * fs


def _hold_and_lag(lin: LinearModel, f: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """``H0 L`` (nf, actuators) and ``z^-1`` (nf,) at frequencies ``f`` [Hz]."""
    wt = 2 * math.pi * f / fs
    z_inv = np.exp(-1j * wt)
    hold = (1 - z_inv) / (1j * wt)
    lag = np.ones((f.size, len(lin.scenario.actuators)), dtype=complex)
    for k, act in enumerate(lin.scenario.actuators):
        if act.bandwidth is not None:
            lag[:, k] = 1.0 / (1.0 + 1j * f / act.bandwidth)
    return hold[:, None] * lag, z_inv


def _controller_response(controller: SampledController, q: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``K(z)`` (nf, actuators, sensors), times ``z^-1`` with the design's delay."""
    a, b, c, d = (np.asarray(x, dtype=float) for x in controller.matrices(q))
    n = a.shape[0]
    k = np.broadcast_to(d.astype(complex), (z.size, *d.shape)).copy()
    if n:
        x = np.linalg.solve(z[:, None, None] * np.eye(n) - a[None], np.broadcast_to(b.astype(complex),
                                                                                   (z.size, *b.shape)))
        k += c[None] @ x
    if controller.delay:
        k /= z[:, None, None]
    return k


def source_responses(lin: LinearModel, sources: Sequence[Source], outputs: Sequence[str], frequency_hz: np.ndarray,
                     controller: SampledController | None = None) -> np.ndarray:
    """Each source's complex response at each output (the linear model's point outputs, displacement [m] per
    source unit), passive or through the controller's loop.

    Returns
    -------
    ndarray (nf, outputs, sources)
    """
    f = np.asarray(frequency_hz, dtype=float)
    physical = [k for k, s in enumerate(sources) if s.inputs is not None]
    w = np.zeros((len(lin.input_names), len(physical)))
    for column, k in enumerate(physical):
        w[:, column] = np.asarray(sources[k].inputs)
    h = lin.frequency_response(f, None, outputs)  # (nf, outputs, inputs)
    out = np.zeros((f.size, len(outputs), len(sources)), dtype=complex)
    out[:, :, physical] = h @ w
    if controller is None:
        return out
    fs = float(controller.sample_rate)
    iu, _ = _indices(lin)
    s_all = lin.sensor_response(f)  # (nf, sensors, inputs), each in its quantity
    held, z_inv = _hold_and_lag(lin, f, fs)
    m_pa = h[:, :, iu] * held[:, None, :]
    p_sa = s_all[:, :, iu]
    _, ys = _indices(lin)
    d_sa = np.asarray(lin.system.D, dtype=float)[np.ix_(ys, iu)]
    m_sa = p_sa * held[:, None, :]
    for k, act in enumerate(lin.scenario.actuators):
        if act.bandwidth is None and np.any(d_sa[:, k]):
            m_sa[:, :, k] = (p_sa[:, :, k] - d_sa[None, :, k]) * held[:, None, k] + d_sa[None, :, k] * z_inv[:, None]
    k_z = _controller_response(controller, lin.positions, 1.0 / z_inv)
    eye = np.eye(len(iu))
    try:
        x = np.linalg.solve(eye[None] - k_z @ m_sa, k_z)  # (nf, actuators, sensors)
    except np.linalg.LinAlgError:
        raise ParameterError("controller: the loop I - K M is singular at some frequency of the band") from None
    gain = m_pa @ x  # (nf, outputs, sensors): a reading's offset to the points
    out[:, :, physical] += gain @ (s_all @ w)
    for k, source in enumerate(sources):
        if source.sensor is not None:
            out[:, :, k] = gain[:, :, source.sensor]
    return out
