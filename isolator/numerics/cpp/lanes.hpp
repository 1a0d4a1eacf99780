/* Doubles side by side for the DOP853 stepping loop (dop853_loop.cpp): V, the runs' values, and S, the
   values the signals are computed in.

   Included (textually, by isolator/numerics/dop853_driver.py) after `#define LANES n` and `#define SLOTS w`
   and before casadi's generated code. Lanes<N> is a struct around a GCC/Clang vector of N doubles:
   arithmetic, comparisons (1.0 / 0.0 per lane, as casadi expects) and the math functions casadi emits,
   lane by lane where there is no vector instruction (friends, found by argument-dependent lookup, so
   that a double meets a Lanes<N> through its constructor).
   - LANES == 1 (one run): V is a plain double, and S is Lanes<SLOTS>: the signals of SLOTS sample slots
     of one step at once;
   - LANES > 1 (runs side by side): V and S are Lanes<LANES>, the signals of one slot of every run.
   worst(a, b) is max(a, b) that keeps a NaN in a (the loop's peaks). */
#include <math.h>

template <int N> struct Raw {
  typedef double type __attribute__((vector_size(8 * N), aligned(8)));
  typedef long long mask __attribute__((vector_size(8 * N)));
};

#define LANEWISE(f) friend Lanes f(Lanes a) { Lanes r; for (int i = 0; i < N; ++i) r.v[i] = ::f(a.v[i]); return r; }
#define LANEWISE2(f) \
  friend Lanes f(Lanes a, Lanes b) { Lanes r; for (int i = 0; i < N; ++i) r.v[i] = ::f(a.v[i], b.v[i]); return r; }
template <int N> struct Lanes {
  typedef typename Raw<N>::type raw;
  raw v;
  Lanes() = default;
  Lanes(raw x) : v(x) {}
  Lanes(double d) : v(raw{} + d) {}
  Lanes(int d) : v(raw{} + (double)d) {}
  static Lanes truth(typename Raw<N>::mask m) { return m ? raw{} + 1.0 : raw{}; }
  friend Lanes operator+(Lanes a, Lanes b) { return a.v + b.v; }
  friend Lanes operator-(Lanes a, Lanes b) { return a.v - b.v; }
  friend Lanes operator*(Lanes a, Lanes b) { return a.v * b.v; }
  friend Lanes operator/(Lanes a, Lanes b) { return a.v / b.v; }
  friend Lanes operator-(Lanes a) { return -a.v; }
  friend Lanes operator+(Lanes a) { return a; }
  friend Lanes operator<(Lanes a, Lanes b) { return truth(a.v < b.v); }
  friend Lanes operator<=(Lanes a, Lanes b) { return truth(a.v <= b.v); }
  friend Lanes operator>(Lanes a, Lanes b) { return truth(a.v > b.v); }
  friend Lanes operator>=(Lanes a, Lanes b) { return truth(a.v >= b.v); }
  friend Lanes operator==(Lanes a, Lanes b) { return truth(a.v == b.v); }
  friend Lanes operator!=(Lanes a, Lanes b) { return truth(a.v != b.v); }
  friend Lanes operator!(Lanes a) { return truth(a.v == 0); }
  friend Lanes operator&&(Lanes a, Lanes b) { return truth((a.v != 0) & (b.v != 0)); }
  friend Lanes operator||(Lanes a, Lanes b) { return truth((a.v != 0) | (b.v != 0)); }
  friend Lanes fmax(Lanes a, Lanes b) { return (a.v > b.v) | (b.v != b.v) ? a.v : b.v; }
  friend Lanes fmin(Lanes a, Lanes b) { return (a.v < b.v) | (b.v != b.v) ? a.v : b.v; }
  friend Lanes fabs(Lanes a) { return a.v < 0 ? -a.v : a.v; }
  friend Lanes worst(Lanes a, Lanes b) { return (a.v > b.v) | (a.v != a.v) ? a.v : b.v; }
  friend double lane_of(Lanes a, int l) { return a.v[l]; }
  friend void set_lane(Lanes& a, int l, double value) { a.v[l] = value; }
  LANEWISE(sqrt) LANEWISE(sin) LANEWISE(cos) LANEWISE(tan) LANEWISE(asin) LANEWISE(acos) LANEWISE(atan)
  LANEWISE(exp) LANEWISE(log) LANEWISE(tanh) LANEWISE(sinh) LANEWISE(cosh) LANEWISE(floor) LANEWISE(ceil)
  LANEWISE2(atan2) LANEWISE2(pow)
};
#undef LANEWISE
#undef LANEWISE2

#if LANES == 1
typedef double V;
typedef Lanes<SLOTS> S;
static inline V worst(V a, V b) { return (a > b || a != a) ? a : b; }
static inline double lane_of(V a, int) { return a; }
static inline void set_lane(V& a, int, double value) { a = value; }
#else
typedef Lanes<LANES> V;
typedef V S;
#endif
#define casadi_real V
#ifndef __STDC_VERSION__
#define __STDC_VERSION__ 199901L  /* casadi's helpers then call fmax/fabs, which Lanes<N> overloads */
#endif
