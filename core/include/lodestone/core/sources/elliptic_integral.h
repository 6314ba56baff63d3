#pragma once
// Bulirsch's general complete elliptic integral cel(kc, p, a, b) and the
// complete integrals K and E built on it. Host- and device-usable, no
// allocation, no exceptions. Used by the closed-form field of a uniformly
// magnetized cylinder (Derby & Olbert 2010, Am. J. Phys. 78, 229).
//
//   cel(kc, p, a, b) = integral over phi in [0, pi/2] of
//       (a cos^2 phi + b sin^2 phi) / ((cos^2 phi + p sin^2 phi) sqrt(cos^2 phi + kc^2 sin^2 phi))
//
// kc is the complementary modulus (kc^2 = 1 - k^2). For p < 0 the integral is
// taken as a Cauchy principal value. Algorithm: R. Bulirsch, Numer. Math. 13
// (1969) 305, with the stopping rule tightened for double precision.
#include <cmath>

#include "lodestone/core/base/hostdev.h"

namespace lodestone {
inline namespace sources {

namespace detail {

/// The part of Bulirsch's iteration for cel(kc, p, a, b) that depends on p, a
/// and b; the modulus sequence (k, em) is shared, so that integrals of one kc
/// can run in one loop (celPair).
template <typename T>
struct CelTerms {
  T pp, aa, bb;
  /// The transformation for p and the first step (k = |kc|).
  LODESTONE_HOSTDEV void start(T kc, T p, T a, T b, T k) {
    using std::sqrt;
    pp = p;
    aa = a;
    bb = b;
    if (p > T(0)) {
      pp = sqrt(p);
      bb = b / pp;
    } else {
      // Principal value for p < 0 (and the p == 0, b == 0 limit): transform to
      // an equivalent integral with positive p (Bulirsch 1969, eq. for p < 0).
      T f = kc * kc;
      T q = T(1) - f;
      const T g = T(1) - pp;
      f -= pp;
      q *= (b - a * pp);
      pp = sqrt(f / g);
      aa = (a - b) / g;
      bb = -q / (g * g * pp) + aa * pp;
    }
    step(k);
  }
  /// One step with kk = k em of the shared sequence.
  LODESTONE_HOSTDEV void step(T kk) {
    const T f = aa;
    aa += bb / pp;
    const T g = kk / pp;
    bb = T(2) * (bb + f * g);
    pp += g;
  }
  LODESTONE_HOSTDEV T value(T em) const {
    return T(1.57079632679489661923132169163975144) * (bb + aa * em) / (em * (em + pp));
  }
};

/// NaN or inf where cel(kc, p, a, b) has no finite value, else 0 (`ok` true).
template <typename T>
LODESTONE_HOSTDEV inline T celSpecial(T kc, T p, T a, T b, bool& ok) {
  ok = false;
  // NAN and HUGE_VAL (not numeric_limits) so that nvcc accepts this in device code.
  if (kc != kc || p != p || a != a || b != b) return static_cast<T>(NAN);
  if (kc == T(0)) return static_cast<T>(HUGE_VAL);
  if (p == T(0) && b != T(0)) return static_cast<T>(NAN);
  ok = true;
  return T(0);
}

/// Runs the shared modulus sequence from k = |kc| to convergence, stepping
/// `n` sets of terms; returns the final em.
template <typename T, int n>
LODESTONE_HOSTDEV inline T celIterate(T k, CelTerms<T> (&terms)[n]) {
  using std::fabs;
  using std::sqrt;
  // Relative tolerance on the AGM-like iteration; convergence is quadratic,
  // so the final error is about tol^2, below double round-off.
  const T tol = sizeof(T) > sizeof(float) ? T(1e-10) : T(1e-5);
  T g = T(1), em = T(1) + k, kk = k;
  for (int iter = 0; iter < 64 && fabs(g - k) > g * tol; ++iter) {
    k = T(2) * sqrt(kk);
    kk = k * em;
    for (int i = 0; i < n; ++i) terms[i].step(kk);
    g = em;
    em += k;
  }
  return em;
}

}  // namespace detail

/// Bulirsch's cel(kc, p, a, b) (dimensionless). Converges quadratically; the
/// number of steps grows like log2(log(1/|kc|)), so kc -> 0 stays cheap and
/// accurate (the integral diverges like ln(4/kc) when b != 0). Returns +inf
/// for kc == 0 exactly, where the integral diverges (unless a and b vanish
/// suitably, which callers must special-case), and NaN for NaN arguments or
/// p == 0 with b != 0 (a non-integrable singularity at phi = pi/2).
template <typename T>
LODESTONE_HOSTDEV inline T cel(T kc, T p, T a, T b) {
  using std::fabs;
  bool ok = false;
  const T special = detail::celSpecial(kc, p, a, b, ok);
  if (!ok) return special;
  const T k = fabs(kc);
  detail::CelTerms<T> terms[1];
  terms[0].start(kc, p, a, b, k);
  return terms[0].value(detail::celIterate(k, terms));
}

/// cel(kc, p1, a1, b1) and cel(kc, p2, a2, b2) of one modulus in one loop
/// (the modulus sequence computed once): the same values, bit for bit, as
/// two calls of cel.
template <typename T>
LODESTONE_HOSTDEV inline void celPair(T kc, T p1, T a1, T b1, T p2, T a2, T b2, T& out1, T& out2) {
  using std::fabs;
  bool ok1 = false, ok2 = false;
  const T s1 = detail::celSpecial(kc, p1, a1, b1, ok1), s2 = detail::celSpecial(kc, p2, a2, b2, ok2);
  if (!ok1 || !ok2) {
    out1 = ok1 ? cel(kc, p1, a1, b1) : s1;
    out2 = ok2 ? cel(kc, p2, a2, b2) : s2;
    return;
  }
  const T k = fabs(kc);
  detail::CelTerms<T> terms[2];
  terms[0].start(kc, p1, a1, b1, k);
  terms[1].start(kc, p2, a2, b2, k);
  const T em = detail::celIterate(k, terms);
  out1 = terms[0].value(em);
  out2 = terms[1].value(em);
}

/// Complete elliptic integral of the first kind K(k), modulus k in [0, 1):
/// K = cel(kc, 1, 1, 1) with kc = sqrt(1 - k^2). +inf at |k| = 1.
template <typename T>
LODESTONE_HOSTDEV inline T ellipticK(T k) {
  using std::sqrt;
  const T kc = sqrt((T(1) - k) * (T(1) + k));
  return cel(kc, T(1), T(1), T(1));
}

/// Complete elliptic integral of the second kind E(k), modulus k in [0, 1]:
/// E = cel(kc, 1, 1, kc^2). E(1) = 1 (handled without the kc = 0 divergence).
template <typename T>
LODESTONE_HOSTDEV inline T ellipticE(T k) {
  using std::sqrt;
  const T kc2 = (T(1) - k) * (T(1) + k);
  if (kc2 == T(0)) return T(1);
  return cel(sqrt(kc2), T(1), T(1), kc2);
}

}  // namespace sources
}  // namespace lodestone
