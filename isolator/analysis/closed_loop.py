"""The sampled loop of a discrete controller on a linear model, exactly as the simulation runs it: the one
computation every closed-loop stability verdict uses (``docs/scenario-format.md``, "Controllers on a bending
top").

:func:`command_plant` is the linear model from the actuators' commands [N] to the scenario's sensors (each
lagged actuator's force a state, a top's elastic modes included when it bends); :func:`sampled_loop` holds
it (zero-order hold, one sample of delay when the controller has it, :func:`~isolator.analysis.sampling.
sample_held`) and closes it with the controller's matrices at the model's rest configuration (a scheduled
controller there). The :class:`SampledLoop` gives the spectral radius (a pneumatic table's held air left
out: no input or sensor reaches it), the largest eigenvalue's frequency ``|arg z| fs / 2 pi`` and the
open-loop mode it comes from (:meth:`SampledLoop.growing_mode`). :func:`check_controller` parks the
carriages (their start or positions within their travel), linearises and closes the loop:
``isolator check-controller``, ``isolator simulate --controller`` (which refuses an unstable loop), the
designs' robustness check and the error budget's closed loop all call it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from isolator.analysis.linear import LinearModel, linearise, rest_positions
from isolator.analysis.modes import modes
from isolator.analysis.sampling import closed_loop_matrix, sample_held
from isolator.analysis.travel import check_travel
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario

__all__ = ["SampledController", "SampledLoop", "check_controller", "command_plant", "held_air", "sampled_loop"]


class SampledController(Protocol):
    """What the sampled loop reads of a discrete controller
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


def command_plant(lin: LinearModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, C, D)`` from the actuators' commands [N] (file order) to the sensors' readings (file order, each
    in its quantity): the linear model's states, then one force state per actuator with a ``bandwidth``
    (``f' = 2 pi bandwidth (u - f)``); an accelerometer reads a lagged force through its state and an unlagged
    one at once (``D``)."""
    inputs, outputs = lin.input_names, lin.output_names
    iu = [inputs.index(f"actuator:{a.name}") for a in lin.scenario.actuators]
    ys = [outputs.index(f"s:{s.name}") for s in lin.scenario.sensors]
    sys = lin.realisation  # its arrays: the python-control system is not needed here
    a, b = np.asarray(sys.a, dtype=float), np.asarray(sys.b, dtype=float)[:, iu]
    c, d = np.asarray(sys.c, dtype=float)[ys], np.asarray(sys.d, dtype=float)[np.ix_(ys, iu)]
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
    c_full = np.hstack([c, d[:, lagged]])
    d_full = np.zeros_like(d)
    d_full[:, direct] = d[:, direct]
    return a_full, b_full, c_full, d_full


def held_air(lin: LinearModel) -> int:
    """The poles at zero of a pneumatic table's linear model (one per leveling group holding its air); 0 for
    a table without air springs."""
    if lin.air is None:
        return 0
    eig = lin.eigenvalues
    return int(np.sum(np.abs(eig) <= 1e-9 * max(1.0, float(np.abs(eig).max()))))


@dataclass(frozen=True)
class SampledLoop:
    """The sampled loop of a controller on a linear model (see the module's description).

    Attributes
    ----------
    lin : LinearModel
        The plant at its rest configuration.
    sample_rate : float
        [Hz]
    plant : tuple of ndarray
        The sampled plant ``(Ap, Bp, Cp, Dp)`` from the commands [N] to the readings: the linear model's
        states, the lag states, then the delayed and applied commands (:func:`sample_held`).
    controller : tuple of ndarray
        ``(Ak, Bk, Ck, Dk)`` at the rest configuration.
    matrix : ndarray
        The loop's state matrix, states ``[plant, controller]``.
    eigenvalues : ndarray
        All of :attr:`matrix`'s eigenvalues ``z``.
    held : int
        The eigenvalues at ``z = 1`` that are a pneumatic table's held air (:func:`held_air`).
    """

    lin: LinearModel
    sample_rate: float
    plant: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
    controller: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
    matrix: np.ndarray
    eigenvalues: np.ndarray
    held: int

    @property
    def poles(self) -> np.ndarray:
        """The eigenvalues without the held air's (the ``held`` ones nearest ``z = 1``)."""
        if not self.held:
            return self.eigenvalues
        return np.delete(self.eigenvalues, np.argsort(np.abs(self.eigenvalues - 1.0))[:self.held])

    @property
    def largest(self) -> int:
        """Index in :attr:`eigenvalues` of the largest ``|z|`` among :attr:`poles` (-1 without any)."""
        poles = self.poles
        if not poles.size:
            return -1
        return int(np.argmin(np.abs(self.eigenvalues - poles[int(np.argmax(np.abs(poles)))])))

    @property
    def spectral_radius(self) -> float:
        """The largest ``|z|`` [-] (stable below 1)."""
        return float(np.max(np.abs(self.poles), initial=0.0))

    @property
    def stable(self) -> bool:
        """Every eigenvalue (the held air's apart) is inside the unit circle."""
        return self.spectral_radius < 1.0

    @property
    def frequency_hz(self) -> float:
        """``|arg z| fs / 2 pi`` of the largest eigenvalue [Hz] (0 when it is real and positive)."""
        k = self.largest
        return 0.0 if k < 0 else abs(float(np.angle(self.eigenvalues[k]))) * self.sample_rate / (2 * math.pi)

    def growing_mode(self) -> tuple[str, float]:
        """The open-loop mode the largest eigenvalue comes from: its name as ``isolator modes`` gives it (the
        dominant coordinate, ``rz``, ``twist 1``, ...) and its frequency [Hz].

        The largest eigenvalue's eigenvector, restricted to the linear model's states, is expanded in the
        open-loop eigenvectors (``x = V q``); each mode's share is the kinetic energy of its part,
        ``|lambda_j q_j|^2 v_j^H M v_j`` over its eigenvalue pair, and the mode with the largest share is named.
        ``("none", nan)`` without an eigenvalue, or when the plant's states take no part (a controller's own
        instability)."""
        k = self.largest
        table = modes(self.lin)
        if k < 0 or not table.eigenvalues.size:
            return "none", math.nan
        a = np.asarray(self.lin.realisation.a, dtype=float)
        lam, vec = np.linalg.eig(a)
        n, ndof = a.shape[0], self.lin.mass.shape[0]
        z, w = np.linalg.eig(self.matrix)
        x = w[:n, int(np.argmin(np.abs(z - self.eigenvalues[k])))]
        try:
            q = np.linalg.solve(vec, x)
        except np.linalg.LinAlgError:
            q = np.linalg.lstsq(vec, x, rcond=None)[0]
        mass = np.abs(np.diag(self.lin.mass))
        energy = np.abs(lam * q) ** 2 * np.sum(mass[:, None] * np.abs(vec[:ndof]) ** 2, axis=0)
        ref = table.eigenvalues
        share = np.zeros(ref.size)
        tol = 1e-6 * max(1.0, float(np.abs(lam).max()))
        for j, value in enumerate(lam):
            gap = np.minimum(np.abs(ref - value), np.abs(ref.conj() - value))
            if gap.min() <= tol:
                share[int(np.argmin(gap))] += energy[j]
        if not np.any(share > 0):
            return "none", math.nan
        best = int(np.argmax(share))
        return table.dominant[best], float(table.frequencies_hz[best])

    def describe(self) -> str:
        """One line: stable with its spectral radius, or the growing oscillation and the mode it comes from."""
        radius, f = self.spectral_radius, self.frequency_hz
        at = f"at {self.sample_rate:.6g} Hz sampling"
        if self.stable:
            return f"the sampled loop is stable: spectral radius {radius:.6g} (largest eigenvalue at {f:.4g} Hz), {at}"
        name, f_mode = self.growing_mode()
        source = (f"from the open-loop mode '{name}' ({f_mode:.4g} Hz)" if name != "none"
                  else "from the controller's own states (no open-loop mode takes part)")
        return (f"the sampled loop is unstable: an oscillation at {f:.4g} Hz grows by |z| = {radius:.6g} per "
                f"sample {at}, {source}")


def sampled_loop(lin: LinearModel, controller: SampledController) -> SampledLoop:
    """Close ``controller`` (its matrices at ``lin``'s rest configuration) around ``lin``'s held plant.

    Parameters
    ----------
    lin : LinearModel
        With the controller's sensors and actuators (names are not checked here: see
        :func:`check_controller`).
    controller : SampledController
        A :class:`~isolator.simulation.discrete_controller.DiscreteController`.

    Returns
    -------
    SampledLoop

    Raises
    ------
    ParameterError
        The loop through the plant's feedthrough has no solution (``I - Dk Dp`` singular).
    """
    fs = float(controller.sample_rate)
    m = len(lin.scenario.actuators)
    az, bz, cz, dz = sample_held(command_plant(lin), m, fs, bool(controller.delay))
    plant = (az, bz[:, :m], cz, dz[:, :m])
    kd = tuple(np.asarray(x, dtype=float) for x in controller.matrices(lin.positions))
    matrix = closed_loop_matrix(plant, kd)
    return SampledLoop(lin, fs, plant, kd, matrix, np.linalg.eigvals(matrix), held_air(lin))  # type: ignore[arg-type]


def check_controller(scenario: Scenario, controller: SampledController,
                     positions: Mapping[str, float] | Sequence[float] | None = None,
                     key: str = "positions") -> SampledLoop:
    """The sampled loop of ``controller`` on ``scenario``'s linear model, the carriages at their start or at
    ``positions`` (within their travel): what ``isolator check-controller`` reports and ``isolator simulate
    --controller`` checks first.

    Parameters
    ----------
    scenario : Scenario
        With the controller's ``[[sensors]]`` and ``[[actuators]]`` (names in file order).
    controller : SampledController
    positions : mapping or sequence, optional
        By carriage name (the others at their start) or one per carriage [m].
    key : str
        The option an error about ``positions`` names.

    Raises
    ------
    ParameterError
        The controller's sensors, actuators or carriages are not the scenario's (naming the first that
        differs); a position beyond a carriage's travel (naming the carriage and its travel).
    """
    controller.check_names(scenario)
    q = rest_positions(scenario, positions)
    if positions is not None:
        check_travel(scenario, q, key)
    return sampled_loop(linearise(scenario, positions=q), controller)


check_public(globals())
