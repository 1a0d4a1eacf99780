"""Fixed-step DOP853 with dense output, compiled: long steps between breakpoints, samples interpolated.

The table's modes are a few hertz, so an eighth-order Runge-Kutta step can be
tens of milliseconds long and still far more accurate than the 1 kHz output
needs. The steps never straddle a profile breakpoint: every segment between
breakpoints gets a whole number of equal steps (:mod:`isolator.numerics.step_plan`),
and each output sample is read from its step's seventh-order continuous
extension (Hairer, Norsett and Wanner, *Solving Ordinary Differential
Equations I*, II.6; the coefficients are those of Hairer's code ``dop853.f``,
:mod:`isolator.numerics.dop853_tableau`, with the dense output rewritten in
powers of the step fraction). The compiled loop
(:mod:`isolator.numerics.dop853_driver`) runs all the steps, the samples they
contain and the six table signals at those samples, for one run or several
side by side; the same steps as a casadi graph
(:mod:`isolator.numerics.dop853_graph`) serve when nothing can be compiled.
"""

from __future__ import annotations

import warnings

import casadi as ca
import numpy as np

from isolator.numerics.dop853_driver import Dop853Driver
from isolator.numerics.dop853_graph import Dop853Graph
from isolator.numerics.dop853_tableau import STAGES, Tableau, dop853_tableau
from isolator.numerics.step_plan import TAIL, StepPlan, step_plan
from isolator.numerics.systems import SteppedSystem, stepped_rhs

__all__ = ["STAGES", "TAIL", "DenseStepper", "StepPlan", "Tableau", "dop853_tableau", "step_plan", "stepped_rhs"]


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
        self.model = model
        self.signals = signals
        self.lanes = lanes
        self.compile = compile
        self.driver: Dop853Driver | None = None
        if compile:
            try:
                self.driver = Dop853Driver(model, signals, lanes)
            except (OSError, RuntimeError) as exc:
                warnings.warn(
                    f"could not compile the DOP853 loop ({exc}); stepping a casadi graph instead (slower)",
                    RuntimeWarning,
                    stacklevel=2,
                )
        #: the casadi-graph form, when the C++ loop could not be built or ``compile`` is False
        self.graph = Dop853Graph(model, signals, compile) if self.driver is None else None

    def signal_values(self, state: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """The six table signals (6,) [m, rad] of one state measured from ``reference`` (the compiled loop's own
        evaluation when there is one, else the casadi function's)."""
        values = None if self.driver is None else self.driver.signal_values(state, reference)
        return np.asarray(self.signals(state, reference), dtype=float).reshape(6) if values is None else values

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

    @staticmethod
    def states_at(plan: StepPlan, polynomials: np.ndarray, times: np.ndarray) -> np.ndarray:
        """The model's states at any ``times`` [s] within the plan, (N, n_states), from the steps' dense
        output (``polynomials`` as :meth:`states` takes them)."""
        count = polynomials.shape[0]
        starts = np.asarray(plan.start, dtype=float)[:count]
        step = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, count - 1)
        s = ((np.asarray(times, dtype=float) - starts[step]) / np.asarray(plan.length, dtype=float)[step])[:, None]
        out = polynomials[step, -1]
        for j in range(polynomials.shape[1] - 2, 0, -1):
            out = polynomials[step, j] + s * out
        return np.asarray(polynomials[step, 0] + s * out)

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
        signals, _, _, polynomials = self.run_slots(x0, plan, inputs, p, reference, with_states=True)
        assert polynomials is not None
        return signals[plan.sample_slots], self.states(plan, polynomials)

    def run_slots(
        self,
        x0: np.ndarray,
        plan: StepPlan,
        inputs: np.ndarray,
        p: np.ndarray,
        reference: np.ndarray,
        with_states: bool = False,
        final: np.ndarray | None = None,
        samples: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
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
        final : ndarray (6,), optional
            The target the deviations are measured from (``(lanes, 6)`` for stacked runs; default 0).
        samples : ndarray (6, samples), optional
            (``(6, samples, lanes)`` for stacked runs, C order) filled from its second column on with the signals
            at the output samples (``signals[plan.sample_slots]``, transposed: a response's rows without a
            gather); its first column, the start, is left as it is.

        Returns
        -------
        signals : ndarray (plan.steps x per_step, 6)
            At every step's used slots (``plan.sample_slots`` picks the samples out, the first
            ``plan.probes`` slots of a step are its probes; the unused slots hold no values).
        peaks : ndarray (plan.steps, 6)
            max |signal| over each step's probes (its samples for a plan without probes;
            0 for a step without one; NaN propagates).
        deviations : ndarray (plan.steps, 6)
            max |signal - final| over the same slots.
        polynomials : ndarray (plan.steps, degree + 1, n_states) or None
            Each step's start state and dense-output coefficients (see :meth:`states`);
            None unless ``with_states``.
        """
        stacked = np.ndim(x0) == 2
        x0, p, reference = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (x0, p, reference))
        target = np.zeros((x0.shape[0], 6)) if final is None else np.atleast_2d(np.asarray(final, dtype=float))
        if x0.shape[0] != self.lanes:
            raise ValueError(f"{x0.shape[0]} runs given to a stepper of {self.lanes} lanes")
        lanes_out = None if samples is None else (samples if stacked else samples.reshape(*samples.shape, 1))
        if lanes_out is not None and not np.may_share_memory(lanes_out, samples):  # a copy would be lost
            raise ValueError("samples: must be a C-ordered float array")
        if self.driver is not None:
            signals, peaks, deviations, polynomials = self.driver.run(
                x0, plan, inputs, p, reference, with_states, target, lanes_out
            )
        else:
            assert self.graph is not None
            runs = [self.graph.run(x0[i], plan, inputs, p[i], reference[i], with_states, target[i])
                    for i in range(self.lanes)]
            signals, peaks, deviations = (np.stack([r[j] for r in runs], axis=-1) for j in range(3))  # type: ignore[misc]
            polys = [r[3] for r in runs]
            polynomials = None if polys[0] is None else np.stack(polys, axis=-1)  # type: ignore[arg-type]
            if lanes_out is not None:
                lanes_out[:, 1:] = np.moveaxis(signals[plan.sample_slots], 0, 1)
        if stacked:
            return signals, peaks, deviations, polynomials
        return (signals[..., 0], peaks[..., 0], deviations[..., 0],
                None if polynomials is None else polynomials[..., 0])
