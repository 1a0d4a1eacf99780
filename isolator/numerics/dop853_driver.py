"""The DOP853 stepping loop in C++: one run, or several side by side in SIMD lanes.

The loop (the stages, the dense output, the samples and their peaks) is C++
source shipped with the package (``cpp/dop853_loop.cpp``, ``cpp/lanes.hpp``);
this module puts it together with two casadi-generated functions (the model's
right-hand side and the table signals of a state) and the tableau's
coefficients, unrolled as macros, through the template ``cpp/dop853_driver.cpp.j2``
(:func:`~isolator.numerics.rendering.render`), compiles it and calls it. Compiled with
``casadi_real`` a vector of ``lanes`` doubles (GCC/Clang vector extensions), the same source steps
``lanes`` runs that share a step plan and staged inputs, such as the runs of
a batch whose isolators differ, with one instruction stream. With AVX, four
runs cost little more than one. A single run (``lanes=1``) steps in plain doubles and
computes the signals of its sample slots :func:`~isolator.numerics.native.vector_lanes` at a
time instead: the signals' code generated apart from the right-hand side's, with ``casadi_real`` a
vector of slots (the slots' dense output and signals were a third of a run's loop computed one at a time).

Layouts (C order): per-run arrays are interleaved by lane, ``(values, lanes)``;
shared arrays (stage inputs, step lengths, sample fractions) are plain.
"""

from __future__ import annotations

import ctypes

import casadi as ca
import numpy as np

from isolator.numerics.dop853_tableau import STAGES, dop853_tableau
from isolator.numerics.native import FLAGS, compiled_library, vector_lanes
from isolator.numerics.rendering import render
from isolator.numerics.step_plan import StepPlan
from isolator.numerics.systems import SteppedSystem, stepped_rhs

__all__ = ["Dop853Driver", "driver_source", "signal_rows"]


def signal_rows(signals: ca.Function, n_states: int) -> list[int]:
    """The states the table signals depend on (the others need no dense output for the samples)."""
    x, reference = ca.SX.sym("x", n_states), ca.SX.sym("r", n_states)
    return sorted(set(ca.jacobian(signals(x, reference), x).sparsity().get_col()))


def _nonzero(weights: np.ndarray) -> list[tuple[int, float]]:
    """The nonzero weights of a tableau row as (stage, weight) pairs."""
    return [(i, float(w)) for i, w in enumerate(weights) if w != 0.0]


def _sized(function: ca.Function) -> dict[str, int]:
    return {
        "ARG": function.sz_arg(), "RES": function.sz_res(), "IW": function.sz_iw() + 1, "W": function.sz_w() + 1
    }


def driver_source(name: str, model: SteppedSystem, signals: ca.Function, lanes: int) -> str:
    """The C++ source of :class:`Dop853Driver`: ``cpp/lanes.hpp``, casadi's code for the right-hand
    side and the signals (for one run, the signals' apart, in vectors of slots), the definitions the loop
    expects (sizes, names, the unrolled stages and dense output), then ``cpp/dop853_loop.cpp``.

    Parameters
    ----------
    name : str
        The exported function's name (the casadi functions get it as a prefix).
    model : SteppedSystem
        Stepped through its staged right-hand side when it has one, else through ``rhs``.
    signals : casadi.Function
        ``(x, reference) -> (6,)``.
    lanes : int
        Runs per call (1: plain doubles).
    """
    tab = dop853_tableau()
    rhs = stepped_rhs(model)
    nx = model.n_states
    functions = []
    for suffix, f in (("rhs", rhs), ("signals", signals)):
        if f.is_a("SXFunction"):
            sx = f.sx_in()
            functions.append(ca.Function(f"{name}_{suffix}", sx, f.call(sx)))
        else:
            mx = f.mx_in()
            functions.append(ca.Function(f"{name}_{suffix}", mx, f.call(mx)))
    # one run: the signals apart, computed in vectors of slots (one file name, so one prefix: the helper macros
    # they repeat are the same); runs side by side: both in one piece, computed in vectors of runs
    code = []
    for part in ([functions[:1], functions[1:]] if lanes == 1 else [functions]):
        generator = ca.CodeGenerator(f"{name}.c", {"with_header": False})
        for f in part:
            generator.add(f)
        code.append(generator.dump())
    rows = signal_rows(signals, nx)
    others = [j for j in range(nx) if j not in rows]
    defines = {"NX": nx, "NU": rhs.size1_in(1), "ST": STAGES, "DEG": tab.dense.shape[1], "END": tab.end,
               "NROWS": len(rows), "NOTHERS": len(others)}
    defines |= {f"RHS_{k}": v for k, v in _sized(functions[0]).items()}
    defines |= {f"SIG_{k}": v for k, v in _sized(functions[1]).items()}
    defines |= {"DOP853_NAME": name, "DOP853_RHS": f"{name}_rhs", "DOP853_SIGNALS": f"{name}_signals",
                "DOP853_METRICS": f"{name}_metrics", "DOP853_SIGNAL_VALUES": f"{name}_signal_values",
                "DOP853_ROWS": ", ".join(map(str, rows)), "DOP853_OTHERS": ", ".join(map(str, others or [0]))}
    return render("isolator.numerics", "cpp/dop853_driver.cpp.j2", lanes=lanes, slots=vector_lanes(),
                  casadi=code[0], signals=code[1] if lanes == 1 else "", defines=defines,
                  stages=[_nonzero(tab.a[i, :i]) for i in range(1, STAGES)], end=tab.end,
                  dense=[_nonzero(tab.dense[:, d]) for d in range(tab.dense.shape[1])])


class Dop853Driver:
    """Compiled DOP853 steps of ``lanes`` runs at once (see the module's description).

    Parameters
    ----------
    model : SteppedSystem
    signals : casadi.Function
        ``(x, reference) -> (6,)``: the table signals of a state (SX).
    lanes : int
        Runs per call: 1, or 4 for AVX's four doubles.

    Raises
    ------
    RuntimeError
        No C++ compiler, or it failed.
    OSError
        The library does not load.
    """

    def __init__(self, model: SteppedSystem, signals: ca.Function, lanes: int = 1) -> None:
        self.model = model
        self.lanes = lanes
        rhs = stepped_rhs(model)
        self.n_inputs = rhs.size1_in(1)
        self.n_parameters = rhs.size1_in(2)
        self.name = f"isolator_dop853_{model.tag}_l{lanes}"
        self.library = compiled_library(self.name, driver_source(self.name, model, signals, lanes), FLAGS, "c++")
        library = ctypes.CDLL(str(self.library))
        fn = getattr(library, self.name)
        fn.restype = ctypes.c_int
        fn.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_int] + [ctypes.c_void_p] * 12 + [ctypes.c_int,
                                                                                            ctypes.c_void_p]
        self._fn = fn
        metrics = getattr(library, f"{self.name}_metrics")
        metrics.restype = ctypes.c_int
        metrics.argtypes = ([ctypes.c_int] * 3 + [ctypes.c_void_p] * 2 + [ctypes.c_double] + [ctypes.c_void_p] * 6
                            + [ctypes.c_double] * 2 + [ctypes.c_void_p] * 5)
        self._metrics = metrics
        self._signal_values = None
        if lanes == 1:
            values = getattr(library, f"{self.name}_signal_values")
            values.restype, values.argtypes = ctypes.c_int, [ctypes.c_void_p] * 3
            self._signal_values = values

    def signal_values(self, state: np.ndarray, reference: np.ndarray) -> np.ndarray | None:
        """The six table signals (6,) [m, rad] of one state measured from ``reference`` (n_states each), computed
        as the loop computes its samples; None for a driver of several lanes."""
        if self._signal_values is None:
            return None
        x, ref = (np.ascontiguousarray(a, dtype=float).reshape(-1) for a in (state, reference))
        if x.size != self.model.n_states or ref.size != self.model.n_states:
            raise ValueError(f"{self.name}: a state and a reference of {self.model.n_states} values each")
        out = np.empty(6)
        self._signal_values(x.ctypes.data, ref.ctypes.data, out.ctypes.data)
        return out

    def run(
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
        """Step ``lanes`` runs through ``plan``.

        Parameters
        ----------
        x0 : ndarray (lanes, n_states)
            States at t = 0.
        plan : StepPlan
        inputs : ndarray (steps, stages, input size)
            The model's (staged) inputs at every stage time, shared by the lanes.
        p : ndarray (lanes, parameters)
        reference : ndarray (lanes, n_states)
            The states the signals are measured from.
        with_states : bool
            Also return each step's dense-output polynomial.
        final : ndarray (lanes, 6), optional
            The target of the deviations (default zero).
        samples : ndarray (6, samples, lanes), optional
            Filled from its second column on with the signals at the plan's output samples (``plan.sample_slots``
            in order; the first column, the start, is left as it is), C order.

        Returns
        -------
        signals : ndarray (plan.steps x per_step, 6, lanes)
            At every step's used sample slots (the others are not written).
        peaks : ndarray (plan.steps, 6, lanes)
            max |signal| over each step's probes (``plan.probes``; over its samples for a plan
            without probes; 0 for a step without one; NaN propagates).
        deviations : ndarray (plan.steps, 6, lanes)
            max |signal - final| over the same slots.
        polynomials : ndarray (plan.steps, degree + 1, n_states, lanes) or None
            Each step's start state and dense-output coefficients.
        """
        steps, m, nx = plan.steps, plan.per_step, self.model.n_states
        target = np.zeros((self.lanes, 6)) if final is None else np.asarray(final, dtype=float)
        lanes = [np.ascontiguousarray(np.asarray(a, dtype=float).T) for a in (x0, p, reference, target)]
        shared = [np.ascontiguousarray(a, dtype=float) for a in (inputs, plan.length, plan.first, plan.fraction)]
        # the compiled loop trusts these sizes
        expected = [(nx, self.lanes), (self.n_parameters, self.lanes), (nx, self.lanes), (6, self.lanes)]
        if [a.shape for a in lanes] != expected or shared[0].shape[1:] != (STAGES, self.n_inputs) or any(
            a.shape[0] < steps for a in shared
        ):
            raise ValueError(f"{self.name}: arrays of the wrong shape for {self.lanes} lanes and {steps} steps")
        signals = np.empty((steps * m, 6, self.lanes))
        peaks = np.empty((steps, 6, self.lanes))
        deviations = np.empty((steps, 6, self.lanes))
        degree = dop853_tableau().dense.shape[1]
        polys = np.empty((steps, degree + 1, nx, self.lanes)) if with_states else None
        x, par, ref, fin = lanes
        u, h, first, frac = shared
        count = plan.sample_slots.size
        if samples is not None and (samples.shape != (6, count + 1, self.lanes) or samples.dtype != np.float64
                                    or not samples.flags.c_contiguous):
            raise ValueError(f"{self.name}: samples must be a C-ordered float array (6, {count + 1}, {self.lanes})")
        self._fn(
            steps, m, plan.probes, x.ctypes.data, u.ctypes.data, h.ctypes.data, first.ctypes.data,
            frac.ctypes.data, par.ctypes.data, ref.ctypes.data, fin.ctypes.data, signals.ctypes.data,
            peaks.ctypes.data, deviations.ctypes.data, None if polys is None else polys.ctypes.data,
            count, None if samples is None else samples.ctypes.data,
        )
        return signals, peaks, deviations, polys

    def metrics(
        self,
        plan: StepPlan,
        slots: np.ndarray,
        peaks: np.ndarray,
        deviations: np.ndarray,
        polynomials: np.ndarray,
        reference: np.ndarray,
        target: np.ndarray,
        stop_time: float,
        band: tuple[float, np.ndarray],
        hold: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Peaks and settling of the ``lanes`` runs :meth:`run` stepped, from their dense output
        (``cpp/dense_metrics.cpp``, the rules of :func:`isolator.simulation.dense_metrics.dense_metrics`).

        Parameters
        ----------
        plan : StepPlan
            The plan the runs were stepped through (with probes).
        slots, peaks, deviations, polynomials : ndarray
            What :meth:`run` returned for them (``with_states``).
        reference : ndarray (lanes, n_states)
            The states the signals are measured from.
        target : ndarray (lanes, 6)
            What the deviations were measured from [m or rad].
        stop_time : float
            [s]; inf when a carriage never stops (no settling).
        band : (float, ndarray (6,))
            The band's fraction of each refined peak, or -1 and the fixed half-widths [m or rad].
        hold : ndarray (lanes,)
            [s], as in :func:`isolator.simulation.settling.settling_time`.

        Returns
        -------
        tuple of three ndarray (lanes, 6)
            The peaks, the settling times and how long before the end each signal was last outside its band,
            as :func:`isolator.simulation.dense_metrics.dense_metrics` returns them.
        """
        steps, nx = plan.steps, self.model.n_states
        degree = dop853_tableau().dense.shape[1]
        arrays = [np.ascontiguousarray(a, dtype=float) for a in (slots, peaks, deviations, polynomials)]
        lanes = [np.ascontiguousarray(np.asarray(a, dtype=float).T) for a in (reference, target)]
        fraction, fixed = band
        shared = [np.ascontiguousarray(a, dtype=float) for a in (plan.start, plan.length, fixed, hold)]
        expected = [(steps * plan.per_step, 6, self.lanes), (steps, 6, self.lanes), (steps, 6, self.lanes),
                    (steps, degree + 1, nx, self.lanes), (nx, self.lanes), (6, self.lanes)]
        if [a.shape for a in (*arrays, *lanes)] != expected or shared[2].shape != (6,) or shared[3].shape != (
            self.lanes,
        ) or plan.probes < 1 or steps < 1 or min(shared[0].size, shared[1].size) < steps:  # the C trusts these sizes
            raise ValueError(f"{self.name}: arrays of the wrong shape for the metrics of {self.lanes} lanes")
        out = [np.empty((6, self.lanes)) for _ in range(3)]
        sig, top, dev, poly = arrays
        ref, fin = lanes
        start, length, half, wait = shared
        self._metrics(
            steps, plan.per_step, plan.probes, start.ctypes.data, length.ctypes.data, float(plan.end),
            sig.ctypes.data, top.ctypes.data, dev.ctypes.data, poly.ctypes.data, ref.ctypes.data, fin.ctypes.data,
            float(stop_time), float(fraction), half.ctypes.data, wait.ctypes.data,
            *(o.ctypes.data for o in out),
        )
        return out[0].T, out[1].T, out[2].T
