"""Fixed-step DOP853 with dense output, compiled: long steps between breakpoints, samples interpolated.

The table's modes are a few hertz, so an eighth-order Runge-Kutta step can be
tens of milliseconds long and still far more accurate than the 1 kHz output
needs. The steps never straddle a profile breakpoint: every segment between
breakpoints gets a whole number of equal steps, and each output sample is read
from its step's seventh-order continuous extension (Hairer, Norsett and
Wanner, *Solving Ordinary Differential Equations I*, II.6; the coefficients
are scipy's DOP853 ones, with the dense output rewritten in powers of the step
fraction). The compiled loop (:mod:`isolator.numerics.dop853_driver`) runs all the steps,
the samples they contain and the six table signals at those samples, for one
run or several side by side; the same steps as a casadi graph serve when
nothing can be compiled.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np
from numpy.polynomial import polynomial as poly
from scipy.integrate._ivp import dop853_coefficients as coefficients

from isolator.numerics.native import NativeFunction
from isolator.numerics.rk4 import SteppedSystem

__all__ = ["STAGES", "DenseStepper", "StepPlan", "Tableau", "dop853_tableau", "step_plan", "stepped_rhs"]

#: right-hand-side evaluations per step (twelve, the end point, three for the dense output)
STAGES = coefficients.N_STAGES_EXTENDED
#: steps per call of the casadi-graph form (without a C++ compiler), and of its shorter form that finishes a run
CHUNK = 128
TAIL = 16


@dataclass(frozen=True)
class Tableau:
    """An explicit Runge-Kutta method whose stage ``end`` is the step's new state.

    Attributes
    ----------
    a : ndarray (stages, stages)
        Strictly lower-triangular stage coefficients.
    c : ndarray (stages,)
        Stage times as fractions of the step.
    end : int
        The stage evaluated at the new state (its row of ``a`` holds the weights).
    dense : ndarray (stages, degree)
        ``y(t0 + s h) = y0 + h sum_i K_i sum_j dense[i, j] s^(j+1)`` for ``0 <= s <= 1``.
    """

    a: np.ndarray
    c: np.ndarray
    end: int
    dense: np.ndarray

    @property
    def weights(self) -> np.ndarray:
        return self.a[self.end, : self.end]


@lru_cache(maxsize=1)
def dop853_tableau() -> Tableau:
    """Dormand and Prince's 8(5,3) method with its 7th-order continuous extension, 16 stages.

    Returns
    -------
    Tableau
        Stage 12 is the right-hand side at the new state; stages 13-15 serve
        the dense output only.
    """
    a = np.array(coefficients.A, dtype=float)
    c = np.array(coefficients.C, dtype=float)
    end = coefficients.N_STAGES
    # scipy's form: y = y0 + x (F0 + (1-x) (F1 + x (F2 + (1-x) (F3 + x (F4 + (1-x) (F5 + x F6))))))
    # with F0 = dy, F1 = h K0 - dy, F2 = 2 dy - h (K_end + K0), F3.. = h D K, dy = h sum b K.
    n_f = coefficients.INTERPOLATOR_POWER
    f_of_k = np.zeros((n_f, STAGES))  # F_j = h * f_of_k[j] @ K
    dy = np.zeros(STAGES)
    dy[:end] = a[end, :end]
    f_of_k[0] = dy
    f_of_k[1] = -dy
    f_of_k[1, 0] += 1.0
    f_of_k[2] = 2 * dy
    f_of_k[2, [0, end]] -= 1.0
    f_of_k[3:] = coefficients.D
    x, one_minus_x = np.array([0.0, 1.0]), np.array([1.0, -1.0])
    basis = []
    factor = np.array([1.0])
    for j in range(n_f):  # the polynomial multiplying F_j: x, x(1-x), x^2(1-x), x^2(1-x)^2, ...
        factor = poly.polymul(factor, x if j % 2 == 0 else one_minus_x)
        basis.append(factor)
    powers = np.zeros((n_f, n_f))  # powers[j, k]: coefficient of x^(k+1) in basis j
    for j, b in enumerate(basis):
        powers[j, : b.size - 1] = b[1:]
    return Tableau(a, c, end, f_of_k.T @ powers)


@dataclass(frozen=True)
class StepPlan:
    """Where the steps fall and which samples each one interpolates.

    Attributes
    ----------
    start : ndarray (steps,)
        Step start times [s].
    length : ndarray (steps,)
        Step lengths [s].
    first : ndarray (steps,)
        1.0 where the step starts a segment (after a breakpoint): its first
        stage is evaluated afresh rather than taken from the previous step's end.
    fraction : ndarray (steps, per_step)
        Fractions of the step at which samples are read; -1 marks an unused slot.
    sample_slots : ndarray (samples - 1,)
        Index into the flattened (steps x per_step) outputs of each sample after the first.
    steps : int
        Steps that advance time; the arrays are padded with empty steps (length 0)
        to a whole number of ``TAIL`` steps (for the casadi-graph form of the steps).
    """

    start: np.ndarray
    length: np.ndarray
    first: np.ndarray
    fraction: np.ndarray
    sample_slots: np.ndarray
    steps: int

    @property
    def per_step(self) -> int:
        return int(self.fraction.shape[1])

    @property
    def evaluations(self) -> int:
        """Right-hand-side evaluations of a run."""
        return int(self.steps * (STAGES - 1) + np.count_nonzero(self.first[: self.steps]))

    def stage_times(self) -> tuple[np.ndarray, np.ndarray]:
        """Every step's stage times and its midpoint (which selects the profile piece) [s],
        each (steps, stages)."""
        c = dop853_tableau().c
        times = self.start[:, None] + self.length[:, None] * c[None, :]
        mid = np.broadcast_to((self.start + self.length / 2)[:, None], times.shape)
        return times, mid


def step_plan(samples: np.ndarray, breakpoints: np.ndarray, max_step: float) -> StepPlan:
    """Equal steps of at most ``max_step`` [s] in every segment between breakpoints.

    Parameters
    ----------
    samples : ndarray
        Output times [s], increasing, from 0.
    breakpoints : ndarray
        Times [s] inside the run where an input is not smooth.
    max_step : float
        [s], > 0.
    """
    end = float(samples[-1])
    edges = np.unique(np.concatenate([[0.0], breakpoints[(breakpoints > 0) & (breakpoints < end)], [end]]))
    counts = np.maximum(1, np.ceil(np.diff(edges) / max_step - 1e-9).astype(int))
    lengths = np.diff(edges) / counts
    seg = np.repeat(np.arange(counts.size), counts)
    index = np.arange(seg.size) - np.repeat(np.cumsum(counts) - counts, counts)
    start = edges[seg] + index * lengths[seg]
    length = lengths[seg]
    first = index == 0
    stop = np.append(start[1:], end)
    # a sample belongs to the step it ends or lies inside: start < t <= stop (the first sample is the initial state)
    owner = np.clip(np.searchsorted(stop, samples[1:] - 1e-12 * max(1.0, end), side="left"), 0, start.size - 1)
    counts_per = np.bincount(owner, minlength=start.size)
    per_step = max(1, int(counts_per.max(initial=1)))
    per_step = 4 * math.ceil(per_step / 4)  # fewer variants of the casadi-graph form
    rank = np.arange(owner.size) - np.repeat(np.cumsum(counts_per) - counts_per, counts_per)
    steps = start.size
    padded = TAIL * math.ceil(steps / TAIL)
    fraction = np.full((padded, per_step), -1.0)
    fraction[owner, rank] = np.clip((samples[1:] - start[owner]) / length[owner], 0.0, 1.0)
    pad = padded - steps
    start = np.concatenate([start, np.full(pad, end)])
    length = np.concatenate([length, np.zeros(pad)])
    first = np.concatenate([first, np.ones(pad, dtype=bool)]).astype(float)
    return StepPlan(start, length, first, fraction, owner * per_step + rank, steps)


class DenseStepper:
    """DOP853 steps of one model, ``lanes`` runs at a time: the compiled loop of
    :class:`~isolator.numerics.dop853_driver.Dop853Driver` (C++), else the same steps as a casadi
    graph, compiled as C when there is a C compiler and evaluated by casadi when there is none.

    Parameters
    ----------
    model : SteppedSystem
        Stepped through its staged right-hand side when it has one
        (:attr:`SteppedSystem.staged_rhs`), else through ``rhs``.
    signals : casadi.Function
        ``(x, reference) -> (6,)``: the table signals of a state (SX).
    lanes : int
        Runs per compiled call (1, or 4 for batches: AVX's four doubles).
    compile : bool
        Compile to native code (False: casadi's evaluator).
    """

    def __init__(self, model: SteppedSystem, signals: ca.Function, lanes: int = 1, compile: bool = True) -> None:
        from isolator.numerics.dop853_driver import Dop853Driver

        self.model = model
        self.signals = signals
        self.lanes = lanes
        self.compile = compile
        self.driver: Dop853Driver | None = None
        self._graphs: dict[tuple[int, bool], tuple[NativeFunction, NativeFunction]] = {}
        if compile:
            try:
                self.driver = Dop853Driver(model, signals, lanes)
            except (OSError, RuntimeError) as exc:
                warnings.warn(
                    f"could not compile the DOP853 loop ({exc}); stepping a casadi graph instead (slower)",
                    RuntimeWarning,
                    stacklevel=2,
                )

    @property
    def native(self) -> bool:
        """True when the compiled C++ loop runs the steps."""
        return self.driver is not None

    @staticmethod
    def states(plan: StepPlan, polynomials: np.ndarray) -> np.ndarray:
        """The model's states at the samples after the first, (samples - 1, n_states).

        Parameters
        ----------
        plan : StepPlan
        polynomials : ndarray (steps, degree + 1, n_states)
            Per step: the state at its start, then the dense output's
            coefficients of s, s^2, ... (from :meth:`run_slots`).
        """
        slots = plan.sample_slots
        step = slots // plan.per_step
        s = plan.fraction.ravel()[slots][:, None]
        out = polynomials[step, -1]
        for j in range(polynomials.shape[1] - 2, 0, -1):
            out = polynomials[step, j] + s * out
        return polynomials[step, 0] + s * out

    def run(
        self, x0: np.ndarray, plan: StepPlan, inputs: np.ndarray, p: np.ndarray, reference: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Table signals and states of one run at the samples after the first.

        Parameters
        ----------
        x0 : ndarray (n_states,)
            State at t = 0.
        plan : StepPlan
        inputs : ndarray (steps, stages, input size)
            The model's inputs at every stage time: ``model.staged_inputs``
            of them when the model has a staged form.
        p : ndarray
            Parameter vector.
        reference : ndarray (n_states,)
            The state the signals are measured from.

        Returns
        -------
        signals : ndarray (samples - 1, 6)
        states : ndarray (samples - 1, n_states)
        """
        signals, _, polynomials = self.run_slots(x0, plan, inputs, p, reference, with_states=True)
        return signals[plan.sample_slots], self.states(plan, polynomials)

    def run_slots(
        self,
        x0: np.ndarray,
        plan: StepPlan,
        inputs: np.ndarray,
        p: np.ndarray,
        reference: np.ndarray,
        with_states: bool = False,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """One run, or ``lanes`` runs sharing ``plan`` and ``inputs``, before the samples are picked out.

        Parameters
        ----------
        x0, p, reference : ndarray
            As for :meth:`run`; stacked ``(lanes, size)`` for ``lanes`` runs at once, when the
            outputs get a last axis of lanes.
        plan, inputs
            As for :meth:`run`.
        with_states : bool
            Also return each step's dense-output polynomial.

        Returns
        -------
        signals : ndarray (plan.steps x per_step, 6)
            At every step's used sample slots (``plan.sample_slots`` picks the samples out;
            the unused slots hold no values).
        peaks : ndarray (plan.steps, 6)
            max |signal| over each step's samples (0 for a step without one; NaN propagates).
        polynomials : ndarray (plan.steps, degree + 1, n_states) or None
            Each step's start state and dense-output coefficients (see :meth:`states`);
            None unless ``with_states``.
        """
        stacked = np.ndim(x0) == 2
        x0, p, reference = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (x0, p, reference))
        if x0.shape[0] != self.lanes:
            raise ValueError(f"{x0.shape[0]} runs given to a stepper of {self.lanes} lanes")
        if self.driver is not None:
            out = self.driver.run(x0, plan, inputs, p, reference, with_states)
        else:
            runs = [self._evaluate(x0[i], plan, inputs, p[i], reference[i], with_states) for i in range(self.lanes)]
            out = tuple(None if r[0] is None else np.stack(r, axis=-1) for r in zip(*runs, strict=True))
        return out if stacked else tuple(None if a is None else a[..., 0] for a in out)

    def _graph(self, per_step: int, with_states: bool) -> tuple[NativeFunction, NativeFunction]:
        """The steps as a casadi graph (chunks of ``CHUNK`` and ``TAIL`` steps), compiled as C when allowed."""
        key = (per_step, with_states)
        if key not in self._graphs:
            step = _step_function(self.model, per_step, self.signals, with_states)
            name = f"isolator_dop853_graph_{self.model.tag}_m{per_step}{'_x' if with_states else ''}"
            self._graphs[key] = tuple(  # type: ignore[assignment]
                NativeFunction(_chunk(step, size, f"{name}_{size}"), compile=self.compile) for size in (CHUNK, TAIL)
            )
        return self._graphs[key]

    def _evaluate(
        self, x0: np.ndarray, plan: StepPlan, inputs: np.ndarray, p: np.ndarray, reference: np.ndarray,
        with_states: bool,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """One run through the casadi graph (:meth:`run_slots` without a C++ compiler)."""
        chunk, tail = self._graph(plan.per_step, with_states)
        n, m, nx = plan.start.size, plan.per_step, self.model.n_states  # n: a whole number of TAIL steps
        signals, peaks = np.empty((n * m, 6)), np.empty((n, 6))
        states = np.empty((n, dop853_tableau().dense.shape[1] + 1, nx)) if with_states else None
        x, k_end = x0, np.zeros(nx)
        full = n // CHUNK * CHUNK
        calls = [(lo, CHUNK, chunk) for lo in range(0, full, CHUNK)] + [(lo, TAIL, tail) for lo in range(full, n, TAIL)]
        for lo, size, fn in calls:
            hi = lo + size
            u = inputs[lo:hi] if inputs.shape[-1] else np.zeros((size * STAGES, 0))
            x, k_end, sig, peak, *rest = fn(
                x, k_end, u, plan.length[lo:hi], plan.first[lo:hi], plan.fraction[lo:hi], p, reference
            )
            x, k_end = x.ravel(), k_end.ravel()
            signals[lo * m : hi * m] = sig
            peaks[lo:hi] = peak
            if states is not None:
                states[lo:hi] = rest[0].reshape(size, -1, nx)
        steps = plan.steps
        return signals[: steps * m], peaks[:steps], None if states is None else states[:steps]


def stepped_rhs(model: SteppedSystem) -> ca.Function:
    """The right-hand side the DOP853 steps evaluate, ``(x, inputs, p) -> dx/dt``: the staged one
    (:attr:`SteppedSystem.staged_rhs`, its inputs from ``model.staged_inputs``) when the model has it."""
    return model.staged_rhs if model.staged_rhs is not None else model.rhs


def _step_function(model: SteppedSystem, per_step: int, signals: ca.Function, with_states: bool) -> ca.Function:
    """One DOP853 step and its samples as a casadi function:
    ``(x, k_end, u, h, first, fraction, p, reference) -> (x_new, k_new, signals, peak, [polynomial])``."""
    tab = dop853_tableau()
    rhs = stepped_rhs(model)
    nx, nu, npar = model.n_states, rhs.size1_in(1), rhs.size1_in(2)
    x = ca.MX.sym("x", nx)
    carried = ca.MX.sym("k_end", nx)
    u = ca.MX.sym("u", nu, STAGES)
    h = ca.MX.sym("h")
    first = ca.MX.sym("first")
    fraction = ca.MX.sym("s", 1, per_step)
    p = ca.MX.sym("p", npar)
    reference = ca.MX.sym("x_ref", nx)
    k = [ca.if_else(first, rhs(x, u[:, 0], p), carried, True)]
    for i in range(1, STAGES):
        row = tab.a[i, :i]
        increment = sum((float(w) * k[j] for j, w in enumerate(row) if w != 0.0), ca.MX.zeros(nx))
        xi = x + h * increment
        if i == tab.end:
            x_new = xi
        k.append(rhs(xi, u[:, i], p))
    samples = _sampler(nx, per_step, signals, with_states)
    outputs = samples.call([x, ca.horzcat(*k), h, fraction, reference])
    return ca.Function("dop853_step", [x, carried, u, h, first, fraction, p, reference], [x_new, k[tab.end], *outputs])


def _chunk(step: ca.Function, steps: int, name: str) -> ca.Function:
    """``steps`` DOP853 steps in a row: the carried state and end slope out, every step's outputs."""
    acc = step.mapaccum("acc", steps, [0, 1], [0, 1])
    x0, k0, u, h, first, s, p, r = step.mx_in()
    args = [ca.MX.sym(a.name(), a.shape[0], a.shape[1] * steps) for a in (u, h, first, s)]
    out = acc(x0, k0, *args, ca.repmat(p, 1, steps), ca.repmat(r, 1, steps))
    return ca.Function(name, [x0, k0, *args, p, r], [out[0][:, -1], out[1][:, -1], *out[2:]])


def _sampler(nx: int, per_step: int, signals: ca.Function, with_states: bool) -> ca.Function:
    """``(x0, K, h, s, reference) -> (signals, peak, [polynomial])`` at step fractions ``s`` (scalar code);
    ``peak`` is max |signal| over the used slots (``s >= 0``), 0 if none; ``polynomial`` (n_states, degree + 1)
    holds ``x0`` and the dense output's coefficients."""
    tab = dop853_tableau()
    x0, slopes, h = ca.SX.sym("x0", nx), ca.SX.sym("K", nx, STAGES), ca.SX.sym("h")
    fraction, reference = ca.SX.sym("s", 1, per_step), ca.SX.sym("r", nx)
    coef = h * (slopes @ ca.DM(tab.dense))
    degree = tab.dense.shape[1]
    values, peak = [], ca.SX.zeros(6, 1)
    for m in range(per_step):
        s = ca.fmax(fraction[m], 0.0)
        acc = coef[:, degree - 1]
        for j in range(degree - 2, -1, -1):
            acc = coef[:, j] + s * acc
        values.append(signals(x0 + s * acc, reference))
        peak = ca.fmax(peak, ca.fabs(values[-1]) * (fraction[m] >= 0))
    outputs = [ca.horzcat(*values), peak]
    if with_states:
        outputs.append(ca.horzcat(x0, coef))
    return ca.Function("dop853_samples", [x0, slopes, h, fraction, reference], outputs)
