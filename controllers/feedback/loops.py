"""The loop on the linear plant: closed with a controller, and checked continuous and sampled.

:func:`closed_loop` closes the loop on the linear plant (with the actuators'
first-order lag) for transmissibility and compliance with control;
:func:`check_stability` checks the loop in continuous time and as run, i.e.
the controller discretised (Tustin) at its sample rate around the plant held
by a zero-order hold, and raises :class:`~isolator.errors.UnstableClosedLoopError`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import control
import numpy as np
from scipy.linalg import expm

from isolator.analysis.linear import FORCE_INPUTS, GROUND_INPUTS, LinearModel, is_stable, state_space_response
from isolator.analysis.signal_names import labels, signals, to_control
from isolator.errors import ParameterError, UnstableClosedLoopError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import SIGNALS, Scenario

from .designs import MEASUREMENTS, Controller, actuator_labels

__all__ = ["REFERENCE_INPUTS", "ClosedLoop", "LoopStability", "check_stability", "closed_loop", "lagged_plant"]

REFERENCE_INPUTS = tuple(f"reference:{s}" for s in SIGNALS)


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


def lagged_plant(lin: LinearModel) -> _Plant:
    """The linear table with a first-order lag state per actuator that has a ``bandwidth``, split for feedback:
    commands ``u`` [N] before the lag, disturbances ``w`` (ground and force inputs), the linear model's outputs
    and the measured table states (the fields of :class:`_Plant`)."""
    sys = lin.system
    a, b = np.asarray(sys.A, dtype=float), np.asarray(sys.B, dtype=float)
    c, d = np.asarray(sys.C, dtype=float), np.asarray(sys.D, dtype=float)
    names = labels(sys.input_labels)
    w_names = [*GROUND_INPUTS, *FORCE_INPUTS]
    iw = [names.index(x) for x in w_names]
    iu = [names.index(x) for x in actuator_labels(lin.scenario)]
    acts = lin.scenario.actuators
    lagged = [k for k, act in enumerate(acts) if act.bandwidth is not None]
    nl, n_a = len(lagged), len(acts)
    # lag states f_k' = (u_k - f_k) / tau_k drive the table through the actuator columns
    tau = np.array([1.0 / (2 * math.pi * acts[k].bandwidth) for k in lagged])  # type: ignore[operator]
    bu_table = b[:, iu]
    n = a.shape[0]  # 12 table states, then any chamber pressures of pneumatic isolators
    a_full = np.zeros((n + nl, n + nl))
    a_full[:n, :n] = a
    a_full[:n, n:] = bu_table[:, lagged]
    a_full[n:, n:] = -np.diag(1.0 / tau)
    bu = np.zeros((n + nl, n_a))
    direct = [k for k in range(n_a) if k not in lagged]
    bu[:n, direct] = bu_table[:, direct]
    bu[n + np.arange(nl), lagged] = 1.0 / tau
    bw = np.vstack([b[:, iw], np.zeros((nl, len(iw)))])
    cy = np.hstack([c, np.zeros((c.shape[0], nl))])
    # the sensors see the table's 12 states, the true velocity: the state plus the floor's damper
    # feedthrough, x = xi + B1 g
    cm = np.hstack([np.eye(12), np.zeros((12, n - 12 + nl))])
    dmw = lin.feedthrough[:12, iw]
    return _Plant(a_full, bw, bu, cy, d[:, iw], cm, dmw, w_names, labels(sys.output_labels))


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

    Parameters
    ----------
    lin : LinearModel
        The plant.
    controller : Controller
        The design.
    check : bool
        Check the loop's stability (continuous and sampled) first.

    Returns
    -------
    ClosedLoop
        The loop, with the plant's inputs and outputs: :func:`isolator.transmissibility` and
        :func:`isolator.compliance` take it.

    Raises
    ------
    UnstableClosedLoopError
        With ``check``: the loop is unstable in continuous time or at the
        controller's sample rate.
    """
    p = lagged_plant(lin)
    k = controller.system
    if labels(k.output_labels) != actuator_labels(lin.scenario) or labels(k.input_labels) != list(MEASUREMENTS):
        raise ParameterError("controller: was designed for other actuators or measurements than this plant's")
    _, bk, _, dk = (np.asarray(m, dtype=float) for m in (k.A, k.B, k.C, k.D))
    nk = bk.shape[0]
    # m = Cm x + Dmw w - [ref; 0];  u = Ck xc + Dk m
    ref = np.vstack([np.eye(6), np.zeros((6, 6))])
    a = _loop_matrix(p, controller)
    b = np.block([[p.bw + p.bu @ dk @ p.dmw, -p.bu @ dk @ ref], [bk @ p.dmw, -bk @ ref]])
    c = np.hstack([p.cy, np.zeros((p.cy.shape[0], nk))])
    d = np.hstack([p.dyw, np.zeros((p.cy.shape[0], 6))])
    system = control.ss(a, b, c, d, inputs=signals([*p.inputs, *REFERENCE_INPUTS]), outputs=signals(p.outputs),
                        name=to_control(f"{lin.scenario.name} with {controller.name}"))
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
    controller : str
        The controller's name.
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
    """Check the loop of ``controller`` around ``lin`` continuous and sampled.

    Parameters
    ----------
    lin : LinearModel
        The plant.
    controller : Controller
        The design.
    where : str
        Where the plant is (e.g. the carriages' positions), for the report and the error.

    Returns
    -------
    LoopStability
        Whether the loop is stable in continuous time and sampled at the controller's rate (the largest
        closed-loop pole's real part and spectral radius).
    """
    p = lagged_plant(lin)
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
    continuous, sampled = np.linalg.eigvals(a_cont), np.linalg.eigvals(a_disc)
    neutral = _air_integrators(lin)
    if neutral:  # the air each leveling group holds: no input or sensor reaches it, it stays where it is
        continuous = np.delete(continuous, np.argsort(np.abs(continuous))[:neutral])
        sampled = np.delete(sampled, np.argsort(np.abs(sampled - 1.0))[:neutral])
    return LoopStability(continuous, sampled, controller.sample_rate, controller.name, where)


def _air_integrators(lin: LinearModel) -> int:
    """Pneumatic plants: the open loop's poles at zero, one per leveling group with its valve closed."""
    if lin.air is None:
        return 0
    eig = lin.eigenvalues
    return int(np.sum(np.abs(eig) <= 1e-9 * max(1.0, float(np.abs(eig).max()))))


check_public(globals())
