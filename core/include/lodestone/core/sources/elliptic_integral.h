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

/// Bulirsch's cel(kc, p, a, b) (dimensionless). Converges quadratically; the
/// number of steps grows like log2(log(1/|kc|)), so kc -> 0 stays cheap and
/// accurate (the integral diverges like ln(4/kc) when b != 0). Returns +inf
/// for kc == 0 exactly, where the integral diverges (unless a and b vanish
/// suitably, which callers must special-case), and NaN for NaN arguments or
/// p == 0 with b != 0 (a non-integrable singularity at phi = pi/2).
template <typename T>
LODESTONE_HOSTDEV inline T cel(T kc, T p, T a, T b) {
  using std::fabs;
  using std::sqrt;
  // NAN and HUGE_VAL (not numeric_limits) so that nvcc accepts this in device code.
  if (kc != kc || p != p || a != a || b != b) return static_cast<T>(NAN);
  if (kc == T(0)) return static_cast<T>(HUGE_VAL);
  if (p == T(0) && b != T(0)) return static_cast<T>(NAN);
  // Relative tolerance on the AGM-like iteration; convergence is quadratic,
  // so the final error is about tol^2, below double round-off.
  const T tol = sizeof(T) > sizeof(float) ? T(1e-10) : T(1e-5);
  T k = fabs(kc);
  T pp = p, aa = a, bb = b;
  T em = T(1);
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
  T f = aa;
  aa += bb / pp;
  T g = k / pp;
  bb = T(2) * (bb + f * g);
  pp += g;
  g = em;
  em += k;
  T kk = k;
  for (int iter = 0; iter < 64 && fabs(g - k) > g * tol; ++iter) {
    k = T(2) * sqrt(kk);
    kk = k * em;
    f = aa;
    aa += bb / pp;
    g = kk / pp;
    bb = T(2) * (bb + f * g);
    pp += g;
    g = em;
    em += k;
  }
  return T(1.57079632679489661923132169163975144) * (bb + aa * em) / (em * (em + pp));
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
