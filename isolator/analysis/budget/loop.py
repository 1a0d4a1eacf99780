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

import numpy as np

from isolator.analysis.closed_loop import SampledController, sampled_loop
from isolator.analysis.elastic_outputs import sensor_shapes
from isolator.analysis.linear import LinearModel
from isolator.analysis.sensor_outputs import displacement_rows
from isolator.errors import ParameterError, UnstableClosedLoopError
from isolator.model.rotations import pose_rotation

from .sources import Source

__all__ = ["Resolvent", "SampledController", "SourceResponses", "closed_loop_poles"]


#: largest condition number of an eigenvector basis the responses are evaluated in (else: one solve each)
_MODAL_CONDITION = 1e8


class Resolvent:
    """``C (s I - A)^-1 B`` at many ``s``, in the eigenvector basis of ``A`` when it is well conditioned (one
    ``n``-term sum per frequency instead of a solve), else by batched solves.

    Parameters
    ----------
    a : ndarray (n, n)
    b : ndarray (n, m)
    c : ndarray (p, n)
    """

    def __init__(self, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> None:
        self.a, self.b, self.c = a, b, c
        self.modal: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        if a.shape[0] == 0:
            return
        w, v = np.linalg.eig(a)
        if np.linalg.cond(v) < _MODAL_CONDITION:
            self.modal = (w, c @ v, np.linalg.solve(v, b))

    def __call__(self, s: np.ndarray) -> np.ndarray:
        """(ns, p, m) complex."""
        s = np.asarray(s, dtype=complex)
        if self.a.shape[0] == 0:
            return np.zeros((s.size, self.c.shape[0], self.b.shape[1]), dtype=complex)
        if self.modal is not None:
            w, cv, vb = self.modal
            return np.asarray((cv[None] / (s[:, None, None] - w[None, None, :])) @ vb[None])
        n = self.a.shape[0]
        x = np.linalg.solve(s[:, None, None] * np.eye(n) - self.a[None],
                            np.broadcast_to(self.b.astype(complex), (s.size, *self.b.shape)))
        return np.asarray(self.c[None] @ x)


def _indices(lin: LinearModel) -> tuple[list[int], list[int]]:
    """The linear model's input columns of the actuators and output rows of the sensors, in file order."""
    inputs, outputs = lin.input_names, lin.output_names
    return ([inputs.index(f"actuator:{a.name}") for a in lin.scenario.actuators],
            [outputs.index(f"s:{s.name}") for s in lin.scenario.sensors])


def closed_loop_poles(lin: LinearModel, controller: SampledController) -> np.ndarray:
    """The exactly sampled loop's poles as continuous ones, ``s = fs ln z`` [1/s].

    Raises
    ------
    UnstableClosedLoopError
        A pole outside the unit circle (naming the growing frequency and the open-loop mode it comes from).
    """
    loop = sampled_loop(lin, controller)
    z = loop.eigenvalues
    if loop.spectral_radius > 1.0 + 1e-9:  # the one check (isolator check-controller's), its line
        raise UnstableClosedLoopError(f"controller: {loop.describe()}, at this rest configuration: no random "
                                      "motion has a finite RMS")
    z = z[np.abs(z) > 1e-12]
    return np.log(z) * loop.sample_rate


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
    k = Resolvent(a, b, c)(z) + d[None]
    if controller.delay:
        k /= z[:, None, None]
    return k


class SourceResponses:
    """Each source's complex response at each output (the linear model's point outputs, displacement [m] per
    source unit), passive or through the controller's loop; call it with frequencies [Hz].

    The plant's responses come from one resolvent of the linear model's state matrix, from the sources'
    input vectors and the actuators to the points and to the sensors (their displacement rows, times
    ``(j 2 pi f)^k`` for velocity and acceleration sensors, as
    :func:`isolator.analysis.sensor_outputs.sensor_response` does).
    """

    def __init__(self, lin: LinearModel, sources: Sequence[Source], outputs: Sequence[str],
                 controller: SampledController | None = None) -> None:
        self.lin, self.sources, self.controller = lin, tuple(sources), controller
        self.physical = [k for k, src in enumerate(sources) if src.inputs is not None]
        n_in = len(lin.input_names)
        w = np.zeros((n_in, len(self.physical)))
        for column, k in enumerate(self.physical):
            w[:, column] = np.asarray(sources[k].inputs)
        sys = lin.system
        a, b = np.asarray(sys.A, dtype=float), np.asarray(sys.B, dtype=float)
        rows = [lin.output_names.index(o) for o in outputs]
        c_p, d_p = np.asarray(sys.C, dtype=float)[rows], np.asarray(sys.D, dtype=float)[rows]
        self.iu, ys = _indices(lin)
        columns = np.hstack([w, np.eye(n_in)[:, self.iu]]) if controller is not None else w
        self.n_w, self.n_p = w.shape[1], len(rows)
        c_all, d_all = c_p, d_p @ columns
        if controller is not None:
            sensors = lin.scenario.sensors
            c_d, d_d = displacement_rows(sensors, pose_rotation(lin.equilibrium.pose[3:6]), a.shape[0], n_in,
                                         sensor_shapes(lin.scenario))
            c_all = np.vstack([c_p, c_d])
            d_all = np.vstack([d_p, c_d @ lin.feedthrough + d_d]) @ columns
            self.orders = np.array([sen.order for sen in sensors])
            self.d_sa = np.asarray(sys.D, dtype=float)[np.ix_(ys, self.iu)]
        self.resolvent = Resolvent(a, b @ columns, c_all)
        self.feedthrough = d_all

    def __call__(self, frequency_hz: np.ndarray) -> np.ndarray:
        """(nf, outputs, sources) complex."""
        f = np.asarray(frequency_hz, dtype=float)
        jw = 2j * np.pi * f
        full = self.resolvent(jw) + self.feedthrough[None]
        out = np.zeros((f.size, self.n_p, len(self.sources)), dtype=complex)
        out[:, :, self.physical] = full[:, : self.n_p, : self.n_w]
        controller = self.controller
        if controller is None:
            return out
        sensed = full[:, self.n_p:] * jw[:, None, None] ** self.orders[None, :, None]  # each in its quantity
        held, z_inv = _hold_and_lag(self.lin, f, float(controller.sample_rate))
        m_pa = full[:, : self.n_p, self.n_w:] * held[:, None, :]
        p_sa = sensed[:, :, self.n_w:]
        m_sa = p_sa * held[:, None, :]
        d_sa = self.d_sa
        for k, act in enumerate(self.lin.scenario.actuators):
            if act.bandwidth is None and np.any(d_sa[:, k]):
                direct = d_sa[None, :, k]
                m_sa[:, :, k] = (p_sa[:, :, k] - direct) * held[:, None, k] + direct * z_inv[:, None]
        k_z = _controller_response(controller, self.lin.positions, 1.0 / z_inv)
        eye = np.eye(len(self.iu))
        try:
            x = np.linalg.solve(eye[None] - k_z @ m_sa, k_z)  # (nf, actuators, sensors)
        except np.linalg.LinAlgError:
            raise ParameterError("controller: the loop I - K M is singular at some frequency of the band") from None
        gain = m_pa @ x  # (nf, outputs, sensors): a reading's offset to the points
        out[:, :, self.physical] += gain @ sensed[:, :, : self.n_w]
        for k, source in enumerate(self.sources):
            if source.sensor is not None:
                out[:, :, k] = gain[:, :, source.sensor]
        return out
