/* The DOP853 stepping loop: all the fixed steps of a run, the samples they contain (dense output)
   and the six table signals at those samples, for LANES runs side by side (see lanes.hpp).

   Per step: the stages (the right-hand side, in V: one run, or one per lane), the dense output's
   coefficients of the rows the signals read, then the signals at the step's used slots (its probes,
   then its output samples) GROUP at a time: for one run (LANES == 1) SLOTS slots at once, the dense
   output and the signals computed in S, a vector of SLOTS doubles, one slot per lane (a step's last
   group padded with its start); for runs side by side one slot at a time, a lane per run. Each slot's
   signals are then written, in order, to the slots' array, the step's peaks and deviations (over its
   probes) and the output samples; with poly, every state's dense output.

   Assembled by isolator/numerics/dop853_driver.py after lanes.hpp and casadi's generated code, which
   it follows with these definitions:
     LANES, SLOTS, NX, NU, ST, DEG, END
                                    lanes, slots per signal evaluation of one run, states, stage inputs,
                                    stages (16), dense-output degree (7), the stage at the new state (12)
     RHS_ARG .. RHS_W, SIG_*        casadi's work sizes of the two generated functions
     DOP853_NAME                    the exported function; DOP853_RHS, DOP853_SIGNALS: casadi's
                                    right-hand side (x, u, p) -> dx/dt in V and signals (x, ref) -> (6,) in S
     DOP853_STAGES                  stages 1..15, unrolled with the tableau's nonzero coefficients
                                    (stage i: xi = x + h sum_j a[i][j] K[j], K[i] = rhs(xi, u_i))
     DOP853_DENSE                   the dense output's coefficients of s, s^2, ... for state j
     NROWS, DOP853_ROWS             the states the signals depend on (interpolated at every sample)
     NOTHERS, DOP853_OTHERS         the other states (their dense output only when poly is asked for)

   Layouts (C order): per-run arrays are interleaved by lane, (values, LANES); shared arrays (stage
   inputs, step lengths, first-step flags, sample fractions) are plain. */

static inline void rhs(const V* x, const V* u, const V* p, V* out) {
  const V* arg[RHS_ARG]; V* res[RHS_RES]; casadi_int iw[RHS_IW]; V w[RHS_W];
  arg[0] = x; arg[1] = u; arg[2] = p; res[0] = out;
  DOP853_RHS(arg, res, iw, w, 0);
}

/* the six signals out of states x measured from ref, in S: SLOTS states of one run, or one of every run */
static inline void signals_of(const S* x, const S* ref, S* out) {
  const S* arg[SIG_ARG]; S* res[SIG_RES]; casadi_int iw[SIG_IW]; S w[SIG_W];
  arg[0] = x; arg[1] = ref; res[0] = out;
  DOP853_SIGNALS(arg, res, iw, w, 0);
}

/* the same in V (one state per run), computed as the loop computes its slots */
static inline void signals(const V* x, const V* ref, V* out) {
#if LANES == 1
  S xs[NX], rs[NX], os[6];
  for (int j = 0; j < NX; ++j) { xs[j] = x[j]; rs[j] = ref[j]; }
  signals_of(xs, rs, os);
  for (int k = 0; k < 6; ++k) out[k] = lane_of(os[k], 0);
#else
  signals_of(x, ref, out);
#endif
}

/* the dense output's coefficients of s, s^2, ... for state j */
static inline void dense_row(const V K[ST][NX], double h, int j, V coef[DEG][NX]) {
  DOP853_DENSE
}

/* the slots whose signals are computed at once: SLOTS of one run, or one of every run */
#define GROUP (LANES == 1 ? SLOTS : 1)

/* the signals out of GROUP slots of one step at fractions f (unused ones padded), slot i in lane i of S
   (LANES == 1), or one slot of every run: the rows' dense output into xs (the other states stay 0) */
static inline void slot_signals(const V* x, const V coef[DEG][NX], const double* f, const int* rows, const S* R,
                                S* xs, S* out) {
  S s;
#if LANES == 1
  for (int i = 0; i < SLOTS; ++i) s.v[i] = f[i];
#else
  s = f[0];
#endif
  for (int r = 0; r < NROWS; ++r) {
    const int j = rows[r];
    S acc = coef[DEG - 1][j];
    for (int d = DEG - 2; d >= 0; --d) acc = coef[d][j] + s * acc;
    xs[j] = x[j] + s * acc;
  }
  signals_of(xs, R, out);
}

/* slot i's values of S (one per run) */
static inline V slot_value(S a, int i) {
#if LANES == 1
  return a.v[i];
#else
  (void)i;
  return a;
#endif
}

/* steps: steps of the plan; per: sample slots per step; probes: the leading slots of each step the
   peaks are taken over (0: every used slot); x0 (NX, LANES); u (steps, ST, NU); hs, first (steps);
   frac (steps, per), -1 for an unused slot; p (parameters, LANES); ref (NX, LANES); fin (6, LANES): the
   target the deviations are measured from.
   Out: sig (steps * per, 6, LANES) at the used slots; peak (steps, 6, LANES) max |signal| and dev
   (steps, 6, LANES) max |signal - fin| over each step's peak slots (NaN propagates); poly, unless null,
   (steps, DEG + 1, NX, LANES): each step's start state and dense-output coefficients; samp, unless null,
   (6, nsamp + 1, LANES): the signals at the output samples (the used slots after the probes, in order) from
   index 1 (index 0, the start, is the caller's). */
extern "C" int DOP853_NAME(int steps, int per, int probes, const double* x0, const double* u, const double* hs,
                           const double* first, const double* frac, const double* p, const double* ref,
                           const double* fin, double* sig, double* peak, double* dev, double* poly, int nsamp,
                           double* samp) {
  static const int rows[NROWS + 1] = {DOP853_ROWS};
  static const int others[NOTHERS + 1] = {DOP853_OTHERS};
  V x[NX], xi[NX], xn[NX], K[ST][NX], coef[DEG][NX];
  S xs[NX], Rs[NX];
  const V* P = (const V*)p;
  const V* R = (const V*)ref;
  const V* F = (const V*)fin;
  const int counted = probes > 0 ? probes : per;
  long sample = 0;
  for (int j = 0; j < NX; ++j) { x[j] = ((const V*)x0)[j]; xs[j] = 0.0; Rs[j] = R[j]; }
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
    DOP853_STAGES
    for (int r = 0; r < NROWS; ++r) dense_row(K, h, rows[r], coef);
    V top[6], off[6];
    for (int k = 0; k < 6; ++k) { top[k] = 0.0; off[k] = 0.0; }
    int used[GROUP], n = 0;  /* the used slots waiting for their signals */
    double f[GROUP];
    for (int m = 0; m < per; ++m) {
      const double fm = frac[(long)s * per + m];
      if (fm >= 0.0) { used[n] = m; f[n++] = fm; }
      if (n == 0 || (n < GROUP && m < per - 1)) continue;
      for (int i = n; i < GROUP; ++i) f[i] = 0.0;
      S values[6];
      slot_signals(x, coef, f, rows, Rs, xs, values);
      V got[6][GROUP];  /* slot i's signals (one per run) */
      for (int k = 0; k < 6; ++k) for (int i = 0; i < GROUP; ++i) got[k][i] = slot_value(values[k], i);
      for (int i = 0; i < n; ++i) {
        V* out = (V*)sig + ((long)s * per + used[i]) * 6;
        for (int k = 0; k < 6; ++k) out[k] = got[k][i];
      }
      int peaks = 0, from = 0;  /* the slots are in order: the probes (counted) lead, the samples trail */
      while (peaks < n && used[peaks] < counted) ++peaks;
      while (from < n && used[from] < probes) ++from;
      for (int k = 0; k < 6; ++k) for (int i = 0; i < peaks; ++i) {
        top[k] = worst(top[k], fabs(got[k][i]));
        off[k] = worst(off[k], fabs(got[k][i] - F[k]));
      }
      const int count = samp ? (n - from < nsamp - sample ? n - from : (int)(nsamp - sample)) : 0;
      for (int k = 0; k < 6 && count > 0; ++k) {
        V* to = (V*)samp + (long)k * (nsamp + 1) + sample + 1;
        for (int i = 0; i < count; ++i) to[i] = got[k][from + i];
      }
      sample += count;
      n = 0;
    }
    for (int k = 0; k < 6; ++k) { ((V*)peak)[(long)s * 6 + k] = top[k]; ((V*)dev)[(long)s * 6 + k] = off[k]; }
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

#if LANES == 1
/* the six signals out (6) of one state x (NX) measured from ref (NX): what a run's final rest reads */
extern "C" int DOP853_SIGNAL_VALUES(const double* x, const double* ref, double* out) {
  signals(x, ref, out);
  return 0;
}
#endif
