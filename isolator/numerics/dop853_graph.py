"""The DOP853 steps as a casadi graph: what runs them when there is no C++ compiler.

One step and its samples are a casadi function, accumulated over chunks of
``CHUNK`` steps (and ``TAIL`` steps to finish a run); compiled as C when there
is a C compiler, evaluated by casadi when there is none. Same numbers as the
C++ loop of :mod:`isolator.numerics.dop853_driver` up to rounding.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from isolator.numerics.dop853_tableau import STAGES, dop853_tableau
from isolator.numerics.native import NativeFunction
from isolator.numerics.step_plan import TAIL, StepPlan
from isolator.numerics.systems import SteppedSystem, stepped_rhs

__all__ = ["CHUNK", "Dop853Graph"]

#: steps per call of the casadi-graph form (``TAIL`` for the shorter form that finishes a run)
CHUNK = 128


class Dop853Graph:
    """DOP853 steps of one model through casadi graphs, one run at a time.

    Parameters
    ----------
    model : SteppedSystem
    signals : casadi.Function
        ``(x, reference) -> (6,)``: the table signals of a state (SX).
    compile : bool
        Compile the graphs as C (False: casadi's evaluator).
    """

    def __init__(self, model: SteppedSystem, signals: ca.Function, compile: bool = True) -> None:
        self.model = model
        self.signals = signals
        self.compile = compile
        self._graphs: dict[tuple[int, int, bool], tuple[NativeFunction, NativeFunction]] = {}

    def functions(self, per_step: int, with_states: bool, probes: int = 0) -> tuple[NativeFunction, NativeFunction]:
        """The steps as a casadi graph (chunks of ``CHUNK`` and ``TAIL`` steps), compiled as C when allowed."""
        key = (per_step, probes, with_states)
        if key not in self._graphs:
            step = _step_function(self.model, per_step, self.signals, with_states, probes)
            name = f"isolator_dop853_graph_{self.model.tag}_m{per_step}p{probes}{'_x' if with_states else ''}"
            chunk, tail = (
                NativeFunction(_chunk(step, size, f"{name}_{size}"), compile=self.compile) for size in (CHUNK, TAIL)
            )
            self._graphs[key] = (chunk, tail)
        return self._graphs[key]

    def run(
        self, x0: np.ndarray, plan: StepPlan, inputs: np.ndarray, p: np.ndarray, reference: np.ndarray,
        with_states: bool, final: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        """One run (arguments and results as :meth:`isolator.numerics.dop853.DenseStepper.run_slots`
        gives them for one lane)."""
        chunk, tail = self.functions(plan.per_step, with_states, plan.probes)
        n, m, nx = plan.start.size, plan.per_step, self.model.n_states  # n: a whole number of TAIL steps
        signals, peaks, deviations = np.empty((n * m, 6)), np.empty((n, 6)), np.empty((n, 6))
        target = np.zeros(6) if final is None else np.asarray(final, dtype=float)
        states = np.empty((n, dop853_tableau().dense.shape[1] + 1, nx)) if with_states else None
        x, k_end = x0, np.zeros(nx)
        full = n // CHUNK * CHUNK
        calls = [(lo, CHUNK, chunk) for lo in range(0, full, CHUNK)] + [(lo, TAIL, tail) for lo in range(full, n, TAIL)]
        for lo, size, fn in calls:
            hi = lo + size
            u = inputs[lo:hi] if inputs.shape[-1] else np.zeros((size * STAGES, 0))
            x, k_end, sig, peak, deviation, *rest = fn(
                x, k_end, u, plan.length[lo:hi], plan.first[lo:hi], plan.fraction[lo:hi], p, reference, target
            )
            x, k_end = x.ravel(), k_end.ravel()
            signals[lo * m : hi * m] = sig
            peaks[lo:hi] = peak
            deviations[lo:hi] = deviation
            if states is not None:
                states[lo:hi] = rest[0].reshape(size, -1, nx)
        steps = plan.steps
        return signals[: steps * m], peaks[:steps], deviations[:steps], None if states is None else states[:steps]


def _step_function(
    model: SteppedSystem, per_step: int, signals: ca.Function, with_states: bool, probes: int = 0
) -> ca.Function:
    """One DOP853 step and its samples as a casadi function:
    ``(x, k_end, u, h, first, fraction, p, reference, final)
    -> (x_new, k_new, signals, peak, deviation, [polynomial])``."""
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
    final = ca.MX.sym("final", 6)
    k = [ca.if_else(first, rhs(x, u[:, 0], p), carried, True)]
    x_new = x
    for i in range(1, STAGES):
        row = tab.a[i, :i]
        increment = sum((float(w) * k[j] for j, w in enumerate(row) if w != 0.0), ca.MX.zeros(nx))
        xi = x + h * increment
        if i == tab.end:
            x_new = xi
        k.append(rhs(xi, u[:, i], p))
    samples = _sampler(nx, per_step, signals, with_states, probes)
    outputs = samples.call([x, ca.horzcat(*k), h, fraction, reference, final])
    return ca.Function(
        "dop853_step", [x, carried, u, h, first, fraction, p, reference, final], [x_new, k[tab.end], *outputs]
    )


def _chunk(step: ca.Function, steps: int, name: str) -> ca.Function:
    """``steps`` DOP853 steps in a row: the carried state and end slope out, every step's outputs."""
    acc = step.mapaccum("acc", steps, [0, 1], [0, 1])
    x0, k0, u, h, first, s, p, r, f = step.mx_in()
    args = [ca.MX.sym(a.name(), a.shape[0], a.shape[1] * steps) for a in (u, h, first, s)]
    out = acc(x0, k0, *args, ca.repmat(p, 1, steps), ca.repmat(r, 1, steps), ca.repmat(f, 1, steps))
    return ca.Function(name, [x0, k0, *args, p, r, f], [out[0][:, -1], out[1][:, -1], *out[2:]])


def _sampler(nx: int, per_step: int, signals: ca.Function, with_states: bool, probes: int = 0) -> ca.Function:
    """``(x0, K, h, s, reference, final) -> (signals, peak, deviation, [polynomial])`` at step fractions ``s``
    (scalar code); ``peak`` is max |signal| and ``deviation`` max |signal - final| over the first ``probes``
    slots (every used slot, ``s >= 0``, when 0), 0 if none; ``polynomial`` (n_states, degree + 1) holds
    ``x0`` and the dense output's coefficients."""
    tab = dop853_tableau()
    x0, slopes, h = ca.SX.sym("x0", nx), ca.SX.sym("K", nx, STAGES), ca.SX.sym("h")
    fraction, reference, final = ca.SX.sym("s", 1, per_step), ca.SX.sym("r", nx), ca.SX.sym("f", 6)
    counted = probes if probes > 0 else per_step
    coef = h * (slopes @ ca.DM(tab.dense))
    degree = tab.dense.shape[1]
    values, peak, deviation = [], ca.SX.zeros(6, 1), ca.SX.zeros(6, 1)
    for m in range(per_step):
        s = ca.fmax(fraction[m], 0.0)
        acc = coef[:, degree - 1]
        for j in range(degree - 2, -1, -1):
            acc = coef[:, j] + s * acc
        values.append(signals(x0 + s * acc, reference))
        if m < counted:
            peak = ca.fmax(peak, ca.fabs(values[-1]) * (fraction[m] >= 0))
            deviation = ca.fmax(deviation, ca.fabs(values[-1] - final) * (fraction[m] >= 0))
    outputs = [ca.horzcat(*values), peak, deviation]
    if with_states:
        outputs.append(ca.horzcat(x0, coef))
    return ca.Function("dop853_samples", [x0, slopes, h, fraction, reference, final], outputs)
