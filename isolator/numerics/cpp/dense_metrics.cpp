/* Peaks and settling instants of the runs just stepped, from their dense output: the numbers of
   isolator/simulation/dense_metrics.py (its numpy functions are the reference and the fallback), computed
   here so that no polynomial goes through numpy. Included after dop853_loop.cpp (its definitions, rhs,
   signals_of). LANES runs side by side: each lane's points are at its own times, so a point's state is
   gathered lane by lane from its own step's polynomial and the signals are evaluated for all lanes at once;
   one run: SLOTS of its points at once, a point in each lane of S.

   The rules (per signal k and lane l):
   - peak: the largest probe's step (the first largest), its largest probe; the signal at PEAK_POINTS points
     spanning the neighbouring probes (clipped to the run), and the vertex of the parabola through the largest
     point and its neighbours, capped at 1e-6 above the largest point, never below the probes' peak;
   - band: fraction x the refined peak (fraction >= 0), else the fixed half-width;
   - entry interval: the last probe outside the band after the stop (ta) and the next probe (tb, or the run's
     end); the signal at CROSSING_POINTS points across it and the last zero of |s - target| - band placed by
     linear interpolation between the two points around it;
   - a signal outside the band at the end of the run, or last outside less than hold before it, has no
     settling time (NaN). A lane whose probes' peaks are not finite gets them unrefined and no times. */

#define PEAK_POINTS 17
#define CROSSING_POINTS 33

static const int metric_rows[NROWS + 1] = {DOP853_ROWS};

/* the step holding time t and the fraction of it (as StepPlan.locate) */
static void locate(const double* start, const double* length, int steps, double t, int* step, double* f) {
  int lo = 0, hi = steps;  /* the number of starts <= t */
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (start[mid] <= t) lo = mid + 1; else hi = mid;
  }
  int s = lo - 1;
  s = s < 0 ? 0 : (s > steps - 1 ? steps - 1 : s);
  const double h = length[s] > 0.0 ? length[s] : 1.0;
  double x = (t - start[s]) / h;
  *step = s;
  *f = x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
}

/* lanes of S: a point of one run each (LANES == 1), or a run each at one point */
#define S_LANES (LANES == 1 ? SLOTS : LANES)

/* signal k of every lane at count points: t and value (count, LANES); GROUP points at once, each lane's state
   gathered from its own step's polynomial (a last group padded with the last point) */
static void signal_k_at(const double* poly, const double* start, const double* length, int steps, const S* R,
                        int k, int count, const double* t, double* value) {
  S xs[NX], out[6];
  for (int j = 0; j < NX; ++j) xs[j] = 0.0;
  for (int first = 0; first < count; first += GROUP) {
    for (int q = 0; q < S_LANES; ++q) {
      const int i = LANES == 1 && first + q < count ? first + q : (LANES == 1 ? count - 1 : first);
      const int l = LANES == 1 ? 0 : q;
      int step;
      double f;
      locate(start, length, steps, t[(long)i * LANES + l], &step, &f);
      for (int r = 0; r < NROWS; ++r) {
        const int j = metric_rows[r];
        const double* c = poly + ((long)step * (DEG + 1) * NX + j) * LANES + l;
        double acc = c[(long)DEG * NX * LANES];
        for (int d = DEG - 1; d >= 0; --d) acc = c[(long)d * NX * LANES] + f * acc;
        set_lane(xs[j], q, acc);
      }
    }
    signals_of(xs, R, out);
    for (int q = 0; q < S_LANES; ++q) {
      const int i = first + (LANES == 1 ? q : 0);
      if (i < count) value[(long)i * LANES + (LANES == 1 ? 0 : q)] = lane_of(out[k], q);
    }
  }
}

static inline double probe_time(const double* start, const double* length, int probes, int s, int j) {
  return start[s] + length[s] * (j + 1) / probes;
}

/* steps, per, probes, start, length (steps), end: the plan; sig, peak, dev, poly: what the stepping wrote;
   ref (NX, LANES); target (6, LANES): what the deviations were measured from; stop_time [s] (inf: no
   settling); fraction and fixed (6): the band; hold (LANES) [s].
   Out (6, LANES): out_peak [m or rad], out_time (after the stop, NaN where not shown), out_short (how long
   before the end the signal was last outside). */
extern "C" int DOP853_METRICS(int steps, int per, int probes, const double* start, const double* length,
                              double end, const double* sig, const double* peak, const double* dev,
                              const double* poly, const double* ref, const double* target, double stop_time,
                              double fraction, const double* fixed, const double* hold, double* out_peak,
                              double* out_time, double* out_short) {
  S R[NX];
  for (int j = 0; j < NX; ++j) R[j] = ((const V*)ref)[j];
  int ok[LANES];
  double top[6][LANES], refined[6][LANES];
  for (int l = 0; l < LANES; ++l) ok[l] = 1;
  /* the probes' peaks: where, and whether finite */
  int at_step[6][LANES], at_probe[6][LANES];
  for (int k = 0; k < 6; ++k) {
    for (int l = 0; l < LANES; ++l) {
      double best = peak[k * LANES + l];
      int where = 0;
      for (int s = 1; s < steps && best == best; ++s) {
        const double v = peak[((long)s * 6 + k) * LANES + l];
        if (v > best || v != v) { best = v; where = s; }
      }
      top[k][l] = best;
      if (!isfinite(best)) ok[l] = 0;
      int j = 0;
      double largest = -1.0;
      for (int m = 0; m < probes; ++m) {
        const double v = fabs(sig[(((long)where * per + m) * 6 + k) * LANES + l]);
        if (v > largest) { largest = v; j = m; }
      }
      at_step[k][l] = where;
      at_probe[k][l] = j;
    }
  }
  /* the refinement about each signal's largest probe */
  for (int k = 0; k < 6; ++k) {
    double values[PEAK_POINTS][LANES], t[PEAK_POINTS][LANES];
    for (int i = 0; i < PEAK_POINTS; ++i) {
      for (int l = 0; l < LANES; ++l) {
        const int s = at_step[k][l];
        const double centre = probe_time(start, length, probes, s, at_probe[k][l]);
        const double x = centre + (length[s] / probes) * (-1.0 + 0.125 * i);
        t[i][l] = ok[l] ? (x < 0.0 ? 0.0 : (x > end ? end : x)) : 0.0;
      }
    }
    signal_k_at(poly, start, length, steps, R, k, PEAK_POINTS, t[0], values[0]);
    for (int i = 0; i < PEAK_POINTS; ++i) for (int l = 0; l < LANES; ++l) values[i][l] = fabs(values[i][l]);
    for (int l = 0; l < LANES; ++l) {
      if (!ok[l]) { refined[k][l] = top[k][l]; continue; }
      int i = 0;
      double best = values[0][l];
      for (int m = 1; m < PEAK_POINTS; ++m) if (values[m][l] > best) { best = values[m][l]; i = m; }
      i = i < 1 ? 1 : (i > PEAK_POINTS - 2 ? PEAK_POINTS - 2 : i);
      const double a = values[i - 1][l], b = values[i][l], c = values[i + 1][l];
      const double curvature = a - 2.0 * b + c;
      const double vertex = curvature < 0.0 ? b - (a - c) * (a - c) / (8.0 * curvature) : b;
      const double capped = vertex < best * (1 + 1e-6) ? vertex : best * (1 + 1e-6);
      const double above = best > capped ? best : capped;
      refined[k][l] = top[k][l] > above ? top[k][l] : above;
    }
  }
  const int settles = isfinite(stop_time);
  const double threshold = stop_time - 1e-9 * (stop_time > 1.0 ? stop_time : 1.0);
  int first = 0;  /* the first step starting at or after the stop */
  while (settles && first < steps && start[first] < threshold) ++first;
  for (int k = 0; k < 6; ++k) {
    double ta[LANES], tb[LANES], band[LANES];
    int moves[LANES], at_end[LANES];
    for (int l = 0; l < LANES; ++l) {
      const long kl = (long)k * LANES + l;
      out_peak[kl] = refined[k][l];
      out_time[kl] = NAN;
      out_short[kl] = 0.0;
      const double goal = target[kl];
      band[l] = fraction >= 0.0 ? fraction * refined[k][l] : fixed[k];
      ta[l] = tb[l] = 0.0;
      moves[l] = at_end[l] = 0;
      if (!settles || !ok[l]) continue;
      int last = -1;
      for (int s = steps - 1; s >= first; --s) {
        if (dev[((long)s * 6 + k) * LANES + l] > band[l]) { last = s; break; }
      }
      const int after = last >= 0;
      const int at_stop = first > 0 ? fabs(sig[(((long)(first - 1) * per + probes - 1) * 6 + k) * LANES + l] - goal) > band[l]
                                    : fabs(goal) > band[l];
      int next_step = first, next_probe = 0;
      ta[l] = stop_time;
      if (after) {
        int j = probes - 1;  /* the last probe outside (the last probe when none is: as numpy's argmax) */
        for (int m = probes - 1; m >= 0; --m) {
          if (fabs(sig[(((long)last * per + m) * 6 + k) * LANES + l] - goal) > band[l]) { j = m; break; }
        }
        ta[l] = probe_time(start, length, probes, last, j);
        next_step = j < probes - 1 ? last : last + 1;
        next_probe = j < probes - 1 ? j + 1 : 0;
      }
      at_end[l] = next_step >= steps;
      tb[l] = at_end[l] ? end : probe_time(start, length, probes, next_step < steps ? next_step : steps - 1, next_probe);
      moves[l] = after || at_stop;
    }
    if (!settles) continue;
    double tc[CROSSING_POINTS][LANES], gap[CROSSING_POINTS][LANES];
    for (int i = 0; i < CROSSING_POINTS; ++i) {
      for (int l = 0; l < LANES; ++l) tc[i][l] = ta[l] + (tb[l] - ta[l]) * (i / (double)(CROSSING_POINTS - 1));
    }
    signal_k_at(poly, start, length, steps, R, k, CROSSING_POINTS, tc[0], gap[0]);
    for (int i = 0; i < CROSSING_POINTS; ++i) {
      for (int l = 0; l < LANES; ++l) gap[i][l] = fabs(gap[i][l] - target[(long)k * LANES + l]) - band[l];
    }
    for (int l = 0; l < LANES; ++l) {
      const long kl = (long)k * LANES + l;
      if (!ok[l]) continue;
      if (!moves[l]) { out_time[kl] = 0.0; continue; }
      int i = -1;
      for (int m = CROSSING_POINTS - 1; m >= 0; --m) if (gap[m][l] > 0.0) { i = m; break; }
      i = i < 0 ? 0 : (i > CROSSING_POINTS - 2 ? CROSSING_POINTS - 2 : i);
      const double g0 = gap[i][l], g1 = gap[i + 1][l];
      double weight = g0 - g1 > 0.0 ? g0 / (g0 - g1) : 0.0;
      weight = weight < 0.0 ? 0.0 : (weight > 1.0 ? 1.0 : weight);
      const double crossing = tc[i][l] + (tc[i + 1][l] - tc[i][l]) * weight;
      const double short_ = at_end[l] ? 0.0 : end - crossing;
      out_short[kl] = short_;
      out_time[kl] = (at_end[l] || short_ < hold[l]) ? NAN : crossing - stop_time;
    }
  }
  return 0;
}
