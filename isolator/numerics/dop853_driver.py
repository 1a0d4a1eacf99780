"""The DOP853 stepping loop in generated C++: one run, or several side by side in SIMD lanes.

The loop (the stages, the dense output, the samples and their peaks) is
written here around two casadi-generated functions: the model's right-hand
side and the table signals of a state. Compiled with ``casadi_real`` a vector
of ``lanes`` doubles (GCC/Clang vector extensions), the same source steps
``lanes`` runs that share a step plan and staged inputs, such as the runs of
a batch whose isolators differ, with one instruction stream. With AVX, four
runs cost little more than one.

Layouts (C order): per-run arrays are interleaved by lane, ``(values, lanes)``;
shared arrays (stage inputs, step lengths, sample fractions) are plain.
"""

from __future__ import annotations

import ctypes

import casadi as ca
import numpy as np

from isolator.numerics.dop853 import STAGES, StepPlan, dop853_tableau, stepped_rhs
from isolator.numerics.native import FLAGS, compiled_library
from isolator.numerics.rk4 import SteppedSystem

__all__ = ["Dop853Driver", "driver_source", "signal_rows"]

# casadi_real as a struct of `lanes` doubles: arithmetic, comparisons (1.0 / 0.0 per lane, as casadi
# expects) and the math functions casadi emits, lane by lane where there is no vector instruction
_LANE_TYPE = r"""
#include <math.h>
#if LANES == 1
typedef double V;
static inline V worst(V a, V b) { return (a > b || a != a) ? a : b; }
#else
typedef double vraw __attribute__((vector_size(8 * LANES), aligned(8)));
typedef long long vmask __attribute__((vector_size(8 * LANES)));
struct V {
  vraw v;
  V() = default;
  V(vraw x) : v(x) {}
  V(double d) : v(vraw{} + d) {}
  V(int d) : v(vraw{} + (double)d) {}
};
static inline V operator+(V a, V b) { return a.v + b.v; }
static inline V operator-(V a, V b) { return a.v - b.v; }
static inline V operator*(V a, V b) { return a.v * b.v; }
static inline V operator/(V a, V b) { return a.v / b.v; }
static inline V operator-(V a) { return -a.v; }
static inline V operator+(V a) { return a; }
static inline V truth(vmask m) { return m ? vraw{} + 1.0 : vraw{}; }
static inline V operator<(V a, V b) { return truth(a.v < b.v); }
static inline V operator<=(V a, V b) { return truth(a.v <= b.v); }
static inline V operator>(V a, V b) { return truth(a.v > b.v); }
static inline V operator>=(V a, V b) { return truth(a.v >= b.v); }
static inline V operator==(V a, V b) { return truth(a.v == b.v); }
static inline V operator!=(V a, V b) { return truth(a.v != b.v); }
static inline V operator!(V a) { return truth(a.v == 0); }
static inline V operator&&(V a, V b) { return truth((a.v != 0) & (b.v != 0)); }
static inline V operator||(V a, V b) { return truth((a.v != 0) | (b.v != 0)); }
static inline V fmax(V a, V b) { return (a.v > b.v) | (b.v != b.v) ? a.v : b.v; }
static inline V fmin(V a, V b) { return (a.v < b.v) | (b.v != b.v) ? a.v : b.v; }
static inline V fabs(V a) { return a.v < 0 ? -a.v : a.v; }
static inline V worst(V a, V b) { return (a.v > b.v) | (a.v != a.v) ? a.v : b.v; }
#define LANEWISE(f) static inline V f(V a) { V r; for (int i = 0; i < LANES; ++i) r.v[i] = f(a.v[i]); return r; }
LANEWISE(sqrt) LANEWISE(sin) LANEWISE(cos) LANEWISE(tan) LANEWISE(asin) LANEWISE(acos) LANEWISE(atan)
LANEWISE(exp) LANEWISE(log) LANEWISE(tanh) LANEWISE(sinh) LANEWISE(cosh) LANEWISE(floor) LANEWISE(ceil)
static inline V atan2(V a, V b) { V r; for (int i = 0; i < LANES; ++i) r.v[i] = atan2(a.v[i], b.v[i]); return r; }
static inline V pow(V a, V b) { V r; for (int i = 0; i < LANES; ++i) r.v[i] = pow(a.v[i], b.v[i]); return r; }
#endif
#define casadi_real V
#ifndef __STDC_VERSION__
#define __STDC_VERSION__ 199901L  /* casadi's helpers then call fmax/fabs, which V overloads */
#endif
"""

_LOOP = r"""
static inline void rhs(const V* x, const V* u, const V* p, V* out) {
  const V* arg[RHS_ARG]; V* res[RHS_RES]; casadi_int iw[RHS_IW]; V w[RHS_W];
  arg[0] = x; arg[1] = u; arg[2] = p; res[0] = out;
  NAME_rhs(arg, res, iw, w, 0);
}

static inline void signals(const V* x, const V* ref, V* out) {
  const V* arg[SIG_ARG]; V* res[SIG_RES]; casadi_int iw[SIG_IW]; V w[SIG_W];
  arg[0] = x; arg[1] = ref; res[0] = out;
  NAME_signals(arg, res, iw, w, 0);
}

/* the dense output's coefficients of s, s^2, ... for state j */
static inline void dense_row(const V K[ST][NX], double h, int j, V coef[DEG][NX]) {
DENSE
}

extern "C" int NAME(int steps, int per, const double* x0, const double* u, const double* hs,
                    const double* first, const double* frac, const double* p, const double* ref,
                    double* sig, double* peak, double* poly) {
  static const int rows[NROWS + 1] = {ROWS};
  static const int others[NOTHERS + 1] = {OTHERS};
  V x[NX], xi[NX], xn[NX], xs[NX], K[ST][NX], coef[DEG][NX];
  const V* P = (const V*)p;
  const V* R = (const V*)ref;
  for (int j = 0; j < NX; ++j) { x[j] = ((const V*)x0)[j]; xs[j] = 0.0; }
#if LANES > 1
  V ub[ST * NU + 1];
#endif
  for (int s = 0; s < steps; ++s) {
    const double* us = u + (long)s * ST * NU;
#if LANES > 1
    for (int j = 0; j < ST * NU; ++j) ub[j] = us[j];
    const V* uv = ub;
#else
    const V* uv = us;
#endif
    const double h = hs[s];
    if (first[s] != 0.0) rhs(x, uv, P, K[0]);
    else for (int j = 0; j < NX; ++j) K[0][j] = K[END][j];
STAGES
    for (int r = 0; r < NROWS; ++r) dense_row(K, h, rows[r], coef);
    V top[6];
    for (int k = 0; k < 6; ++k) top[k] = 0.0;
    for (int m = 0; m < per; ++m) {
      const double f = frac[(long)s * per + m];
      if (f < 0.0) continue;
      for (int r = 0; r < NROWS; ++r) {
        const int j = rows[r];
        V acc = coef[DEG - 1][j];
        for (int d = DEG - 2; d >= 0; --d) acc = coef[d][j] + f * acc;
        xs[j] = x[j] + f * acc;
      }
      V* out = (V*)sig + ((long)s * per + m) * 6;
      signals(xs, R, out);
      for (int k = 0; k < 6; ++k) top[k] = worst(top[k], fabs(out[k]));
    }
    for (int k = 0; k < 6; ++k) ((V*)peak)[(long)s * 6 + k] = top[k];
    if (poly) {
      for (int r = 0; r < NOTHERS; ++r) dense_row(K, h, others[r], coef);
      V* out = (V*)poly + (long)s * (DEG + 1) * NX;
      for (int j = 0; j < NX; ++j) out[j] = x[j];
      for (int d = 0; d < DEG; ++d) for (int j = 0; j < NX; ++j) out[(d + 1) * NX + j] = coef[d][j];
    }
    for (int j = 0; j < NX; ++j) x[j] = xn[j];
  }
  return 0;
}
"""


def signal_rows(signals: ca.Function, n_states: int) -> list[int]:
    """The states the table signals depend on (the others need no dense output for the samples)."""
    x, reference = ca.SX.sym("x", n_states), ca.SX.sym("r", n_states)
    return sorted(set(ca.jacobian(signals(x, reference), x).sparsity().get_col()))


def _sized(function: ca.Function) -> dict[str, int]:
    return {
        "ARG": function.sz_arg(), "RES": function.sz_res(), "IW": function.sz_iw() + 1, "W": function.sz_w() + 1
    }


def _weighted(weights: np.ndarray, row: str) -> str:
    """``w0 * K[0][j] + w1 * K[1][j] + ...`` over the nonzero weights (``row`` is the index text)."""
    terms = [f"{float(w)!r} * K[{i}][{row}]" for i, w in enumerate(weights) if w != 0.0]
    return " + ".join(terms) if terms else "0.0"


def driver_source(name: str, model: SteppedSystem, signals: ca.Function, lanes: int) -> str:
    """The C++ source of :class:`Dop853Driver` (casadi's code for the right-hand side and the
    signals, then the stepping loop).

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
        args = f.sx_in() if f.is_a("SXFunction") else f.mx_in()
        functions.append(ca.Function(f"{name}_{suffix}", args, f.call(args)))
    generator = ca.CodeGenerator(f"{name}.c", {"with_header": False})
    for f in functions:
        generator.add(f)
    stages = []
    for i in range(1, STAGES):
        stages.append(f"    for (int j = 0; j < NX; ++j) xi[j] = x[j] + h * ({_weighted(tab.a[i, :i], 'j')});")
        stages.append(f"    rhs(xi, uv + {i} * NU, P, K[{i}]);")
        if i == tab.end:
            stages.append("    for (int j = 0; j < NX; ++j) xn[j] = xi[j];")
    dense = "\n".join(
        f"  coef[{d}][j] = h * ({_weighted(tab.dense[:, d], 'j')});" for d in range(tab.dense.shape[1])
    )
    rows = signal_rows(signals, nx)
    others = [j for j in range(nx) if j not in rows]
    loop = _LOOP.replace("STAGES\n", "\n".join(stages) + "\n").replace("DENSE\n", dense + "\n")
    loop = loop.replace("{ROWS}", "{" + ", ".join(map(str, rows)) + "}")
    loop = loop.replace("{OTHERS}", "{" + ", ".join(map(str, others or [0])) + "}")
    defines = {"LANES": lanes, "NX": nx, "NU": rhs.size1_in(1), "ST": STAGES, "DEG": tab.dense.shape[1],
               "END": tab.end, "NROWS": len(rows), "NOTHERS": len(others)}
    defines |= {f"RHS_{k}": v for k, v in _sized(functions[0]).items()}
    defines |= {f"SIG_{k}": v for k, v in _sized(functions[1]).items()}
    head = "".join(f"#define {k} {v}\n" for k, v in defines.items() if k == "LANES")
    body = "".join(f"#define {k} {v}\n" for k, v in defines.items() if k != "LANES")
    return head + _LANE_TYPE + generator.dump() + body + loop.replace("NAME", name)


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
        fn = getattr(ctypes.CDLL(str(self.library)), self.name)
        fn.restype = ctypes.c_int
        fn.argtypes = [ctypes.c_int, ctypes.c_int] + [ctypes.c_void_p] * 10
        self._fn = fn

    def run(
        self,
        x0: np.ndarray,
        plan: StepPlan,
        inputs: np.ndarray,
        p: np.ndarray,
        reference: np.ndarray,
        with_states: bool = False,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
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

        Returns
        -------
        signals : ndarray (plan.steps x per_step, 6, lanes)
            At every step's used sample slots (the others are not written).
        peaks : ndarray (plan.steps, 6, lanes)
            max |signal| over each step's samples (0 for a step without one; NaN propagates).
        polynomials : ndarray (plan.steps, degree + 1, n_states, lanes) or None
            Each step's start state and dense-output coefficients.
        """
        steps, m, nx = plan.steps, plan.per_step, self.model.n_states
        lanes = [np.ascontiguousarray(np.asarray(a, dtype=float).T) for a in (x0, p, reference)]
        shared = [np.ascontiguousarray(a, dtype=float) for a in (inputs, plan.length, plan.first, plan.fraction)]
        # the compiled loop trusts these sizes
        expected = [(nx, self.lanes), (self.n_parameters, self.lanes), (nx, self.lanes)]
        if [a.shape for a in lanes] != expected or shared[0].shape[1:] != (STAGES, self.n_inputs) or any(
            a.shape[0] < steps for a in shared
        ):
            raise ValueError(f"{self.name}: arrays of the wrong shape for {self.lanes} lanes and {steps} steps")
        signals = np.empty((steps * m, 6, self.lanes))
        peaks = np.empty((steps, 6, self.lanes))
        degree = dop853_tableau().dense.shape[1]
        polys = np.empty((steps, degree + 1, nx, self.lanes)) if with_states else None
        x, par, ref = lanes
        u, h, first, frac = shared
        self._fn(
            steps, m, x.ctypes.data, u.ctypes.data, h.ctypes.data, first.ctypes.data, frac.ctypes.data,
            par.ctypes.data, ref.ctypes.data, signals.ctypes.data, peaks.ctypes.data,
            None if polys is None else polys.ctypes.data,
        )
        return signals, peaks, polys
