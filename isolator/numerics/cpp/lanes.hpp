/* casadi_real as `LANES` doubles side by side, for the DOP853 stepping loop (dop853_loop.cpp).

   Included (textually, by isolator/numerics/dop853_driver.py) after `#define LANES n` and before
   casadi's generated code, which then computes in V. With LANES == 1, V is a plain double; else a
   struct around a GCC/Clang vector of LANES doubles: arithmetic, comparisons (1.0 / 0.0 per lane,
   as casadi expects) and the math functions casadi emits, lane by lane where there is no vector
   instruction. worst(a, b) is max(a, b) that keeps a NaN in a (the loop's peaks). */
#include <math.h>
#if LANES == 1
typedef double V;
static inline V worst(V a, V b) { return (a > b || a != a) ? a : b; }
static inline double lane_of(V a, int) { return a; }
static inline void set_lane(V& a, int, double value) { a = value; }
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
static inline double lane_of(V a, int l) { return a.v[l]; }
static inline void set_lane(V& a, int l, double value) { a.v[l] = value; }
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
