"""Classical fourth-order Runge-Kutta: the one step formula, and a compiled fixed-grid stepper.

:func:`rk4_step` is the formula every RK4 in the toolkit uses (the simulation
on the sample grid, the profile optimiser's shooting, the optimal
feedforward's transcription). :class:`Stepper` runs it in compiled code over
a grid of intervals, ``substeps`` steps per interval, in chunks of a fixed
number of intervals; with ``split``, each of a step's four stages takes its own
inputs (the two middle stages, at the same time, may differ: inputs chosen for
what the step integrates, such as an actuator's lag,
:func:`isolator.simulation.actuation.lag_stages`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import casadi as ca
import numpy as np

from isolator.numerics.native import NativeFunction
from isolator.numerics.systems import SteppedSystem

__all__ = ["BY_TIME", "SPLIT", "Motion", "SteppedSystem", "Stepper", "rk4_step", "stage_count"]

CHUNK = 512

X = TypeVar("X")
#: ``(x, reference) -> (12,)``: the sensed motion of a state, casadi
Motion = Callable[[Any, Any], Any]


#: the stage indices ``rates`` is called with: by time (start, middle twice, end), or one per stage
BY_TIME = (0, 1, 1, 2)
SPLIT = (0, 1, 2, 3)


def rk4_step(rates: Callable[[X, int], X], x: X, h: Any, stages: tuple[int, int, int, int] = BY_TIME) -> X:
    """One classical RK4 step of length ``h``.

    Parameters
    ----------
    rates : callable
        ``(x, stage) -> dx/dt`` with ``stage`` from ``stages`` (so that time-dependent inputs are looked up
        per stage).
    x : array or casadi expression
        The state at the step's start.
    h : float or casadi expression
        Step length [s].
    stages : tuple of int
        What ``rates`` is told for the four stages: :data:`BY_TIME` (0 at the step's start, 1 at its middle,
        2 at its end) or :data:`SPLIT` (0, 1, 2, 3: the two middle stages' inputs apart).

    Returns
    -------
    The state at the step's end.
    """
    k1 = rates(x, stages[0])
    k2 = rates(x + h / 2 * k1, stages[1])
    k3 = rates(x + h / 2 * k2, stages[2])
    k4 = rates(x + h * k3, stages[3])
    return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)  # type: ignore[operator]


def stage_count(substeps: int, split: bool = False) -> int:
    """Inputs per grid interval: at the RK4 stage times (``2 substeps + 1``), or four per step (``split``)."""
    return 4 * substeps if split else 2 * substeps + 1


class Stepper:
    """Compiled RK4 stepping of one system with a fixed number of substeps.

    Parameters
    ----------
    model : SteppedSystem
        The right-hand side ``rhs(x, c, p)`` with its state count and tag.
    substeps : int
        RK4 steps per grid interval.
    motion : callable
        ``(x, reference) -> (12,)`` casadi: what motion sensors see (for :meth:`step`).
    compile : bool
        Compile the loop (else casadi evaluates it).
    split : bool
        Four inputs per step, one per stage (:func:`stage_count`), instead of the stage times' ``2 substeps + 1``.
    """

    def __init__(self, model: SteppedSystem, substeps: int, motion: Motion, compile: bool = True,
                 split: bool = False) -> None:
        self.model = model
        self.substeps = substeps
        self.split = split
        nx = model.n_states
        nc = model.rhs.size1_in(1)
        npar = model.rhs.size1_in(2)
        stages = stage_count(substeps, split)
        x = ca.MX.sym("x", nx)
        cin = ca.MX.sym("c", nc, stages)
        h = ca.MX.sym("h")
        p = ca.MX.sym("p", npar)
        dt = h / substeps
        xk = x
        for j in range(substeps):
            first = 4 * j if split else 2 * j
            at = tuple(cin[:, first + k] for k in range(4 if split else 3))

            def rates(xs: ca.MX, k: int, at: tuple[ca.MX, ...] = at) -> ca.MX:
                return model.rhs(xs, at[k], p)

            xk = rk4_step(rates, xk, dt, SPLIT if split else BY_TIME)
        step = ca.Function("step", [x, cin, h, p], [xk])
        reference = ca.MX.sym("x_ref", nx)
        self._step_parts = ([x, cin, h, p, reference], [xk, motion(xk, reference)])
        self._single: Callable[..., list[np.ndarray]] | None = None
        self._compile = compile
        acc = step.mapaccum("acc", CHUNK)
        x0 = ca.MX.sym("x0", nx)
        cc = ca.MX.sym("C", cin.shape[0], stages * CHUNK)
        hh = ca.MX.sym("H", 1, CHUNK)
        pp = ca.MX.sym("p", npar)
        xs = acc(x0, cc, hh, ca.repmat(pp, 1, CHUNK))
        name = f"isolator_{model.tag}_s{substeps}{'_split' if split else ''}"
        self.name = name
        self.chunk = NativeFunction(ca.Function(name, [x0, cc, hh, pp], [xs]), compile=compile)

    def step(
        self, x: np.ndarray, inputs: np.ndarray, h: float, p: np.ndarray, reference: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """One grid interval of length ``h`` [s] with stage inputs (:func:`stage_count`, input size).

        Returns
        -------
        state : ndarray (n_states,)
            At the end of the interval.
        motion : ndarray (12,)
            What motion sensors see there (the ``motion`` function) relative to the state ``reference``.
        """
        if self._single is None:
            fn = ca.Function(f"{self.name}_one", *self._step_parts)
            self._single = NativeFunction(fn, compile=self._compile).bound()
        stages = inputs if inputs.shape[-1] else np.zeros((inputs.shape[0], 0))
        out, motion = self._single(x, stages, h, p, reference)
        return out.ravel().copy(), motion.ravel().copy()

    def run(self, x0: np.ndarray, inputs: np.ndarray, steps: np.ndarray, p: np.ndarray) -> np.ndarray:
        """States at the end of every interval.

        Parameters
        ----------
        x0 : ndarray (n_states,)
        inputs : ndarray (intervals, stage_count(substeps, split), input size)
        steps : ndarray (intervals,)
            Interval lengths [s].
        p : ndarray
            Parameter vector.

        Returns
        -------
        ndarray (intervals, n_states)
        """
        n = steps.size
        nx = self.model.n_states
        out = np.empty((n, nx))
        x = np.asarray(x0, dtype=float)
        stage_shape = inputs.shape[1:]
        for start in range(0, n, CHUNK):
            stop = min(start + CHUNK, n)
            cin = inputs[start:stop]
            hs = steps[start:stop]
            if stop - start < CHUNK:
                pad = CHUNK - (stop - start)
                cin = np.concatenate([cin, np.repeat(cin[-1:], pad, axis=0)])
                hs = np.concatenate([hs, np.zeros(pad)])
            if stage_shape[-1] == 0:
                cin = np.zeros((CHUNK, 0))
            (xs,) = self.chunk(x, cin, hs, p)
            out[start:stop] = xs[: stop - start]
            x = xs[stop - start - 1]
        return out
