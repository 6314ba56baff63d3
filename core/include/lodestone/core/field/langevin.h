#pragma once
// The Langevin function and its relatives, evaluated stably for all arguments
// in float and double (PHYSICS.md section 1).
//
//   L(a)        = coth(a) - 1/a                         (odd, 0 <= L' <= 1/3, L -> 1)
//   L(a)/a      = g(a), the secant slope               (even, g(0) = 1/3)
//   L'(a)       = 1/a^2 - 1/sinh^2(a)                  (even, L'(0) = 1/3)
//   lnsinhc(a)  = ln(sinh(a)/a)                         (even, antiderivative of L)
//
// The textbook forms cancel catastrophically near a = 0 and overflow for large
// a (sinh overflows past a ~ 710 in double, ~ 89 in float). Here, for |a| < 1
// every quantity is a ratio of power series in a^2 whose terms are all
// positive, so nothing cancels:
//   a cosh a - sinh a = a^3 P(a^2),  P = sum 2(j+1)/(2j+3)! x^j
//   sinh(a)/a - 1     = a^2 Q(a^2),  Q = sum 1/(2j+3)! x^j
//   sinh^2 a - a^2    = a^4 S(a^2),  S = sum 2^(2j+3)/(2j+4)! x^j
// giving g = P/(1 + a^2 Q), L' = S/(1 + a^2 S), lnsinhc = log1p(a^2 Q).
// For |a| >= 1 the exponential forms coth a = 1 + 2/expm1(2a) and
// 1/sinh^2 a = 4 e^{-2a}/(1 - e^{-2a})^2 lose at most a few ulps and saturate
// to their limits instead of overflowing.
#include <cmath>
#include <type_traits>

#include "lodestone/core/base/hostdev.h"

namespace lodestone {
inline namespace field {
namespace langevin_series {

template <typename T>
LODESTONE_HOSTDEV constexpr T horner(T /*x*/, T c0) {
  return c0;
}
template <typename T, typename... Rest>
LODESTONE_HOSTDEV constexpr T horner(T x, T c0, Rest... rest) {
  return c0 + x * horner<T>(x, static_cast<T>(rest)...);
}

// Series coefficients generated from exact rationals; 12 terms reach double
// precision for x = a^2 <= 1, 7 terms reach float precision.
template <typename T>
LODESTONE_HOSTDEV constexpr T seriesP(T x) {
  if constexpr (sizeof(T) >= 8) {
    return horner<T>(x, 0.3333333333333333, 0.03333333333333333, 0.0011904761904761906,
                     2.2045855379188714e-05, 2.505210838544172e-07, 1.9270852604185937e-09,
                     1.0706029224547743e-11, 4.498331606952833e-14, 1.4797143443923793e-16,
                     3.9145882126782523e-19, 8.509974375387505e-22, 1.5472680682522736e-24);
  } else {
    return horner<T>(x, 0.3333333333333333, 0.03333333333333333, 0.0011904761904761906,
                     2.2045855379188714e-05, 2.505210838544172e-07, 1.9270852604185937e-09,
                     1.0706029224547743e-11);
  }
}
template <typename T>
LODESTONE_HOSTDEV constexpr T seriesQ(T x) {
  if constexpr (sizeof(T) >= 8) {
    return horner<T>(x, 0.16666666666666666, 0.008333333333333333, 0.0001984126984126984,
                     2.7557319223985893e-06, 2.505210838544172e-08, 1.6059043836821613e-10,
                     7.647163731819816e-13, 2.8114572543455206e-15, 8.22063524662433e-18,
                     1.9572941063391263e-20, 3.868170170630684e-23, 6.446950284384474e-26);
  } else {
    return horner<T>(x, 0.16666666666666666, 0.008333333333333333, 0.0001984126984126984,
                     2.7557319223985893e-06, 2.505210838544172e-08, 1.6059043836821613e-10,
                     7.647163731819816e-13);
  }
}
template <typename T>
LODESTONE_HOSTDEV constexpr T seriesS(T x) {
  if constexpr (sizeof(T) >= 8) {
    return horner<T>(x, 0.3333333333333333, 0.044444444444444446, 0.0031746031746031746,
                     0.00014109347442680775, 4.275559831115387e-06, 9.39683479366019e-08,
                     1.5661391322766984e-09, 2.0472406957865337e-11, 2.1549902060910883e-13,
                     1.8657923862260506e-15, 1.3520234682797467e-17, 8.320144420183057e-20);
  } else {
    return horner<T>(x, 0.3333333333333333, 0.044444444444444446, 0.0031746031746031746,
                     0.00014109347442680775, 4.275559831115387e-06, 9.39683479366019e-08,
                     1.5661391322766984e-09);
  }
}

}  // namespace langevin_series

/// g(a) = L(a)/a, the secant slope of the Langevin function; g(0) = 1/3.
template <typename T>
LODESTONE_HOSTDEV inline T langevinOverArg(T a) {
  static_assert(std::is_floating_point_v<T>, "floating-point argument expected");
  using std::abs;
  using std::expm1;
  const T b = abs(a);
  if (b < T(1)) {
    const T x = b * b;
    return langevin_series::seriesP(x) / (T(1) + x * langevin_series::seriesQ(x));
  }
  // coth(b) - 1/b = 1 - 1/b + 2/expm1(2b); expm1 saturates to +inf, 2/inf = 0.
  return (T(1) - T(1) / b + T(2) / expm1(T(2) * b)) / b;
}

/// L(a) = coth(a) - 1/a.
template <typename T>
LODESTONE_HOSTDEV inline T langevin(T a) {
  static_assert(std::is_floating_point_v<T>, "floating-point argument expected");
  using std::abs;
  using std::expm1;
  const T b = abs(a);
  if (b < T(1)) return a * langevinOverArg(a);
  const T l = T(1) - T(1) / b + T(2) / expm1(T(2) * b);
  return a < T(0) ? -l : l;
}

/// L'(a) = 1/a^2 - 1/sinh^2(a); L'(0) = 1/3, L' -> 1/a^2 for large a.
template <typename T>
LODESTONE_HOSTDEV inline T langevinDerivative(T a) {
  static_assert(std::is_floating_point_v<T>, "floating-point argument expected");
  using std::abs;
  using std::exp;
  using std::expm1;
  const T b = abs(a);
  if (b < T(1)) {
    const T x = b * b;
    const T s = langevin_series::seriesS(x);
    return s / (T(1) + x * s);
  }
  const T e = exp(T(-2) * b);  // underflows to 0 for large b: no overflow anywhere
  const T u = -expm1(T(-2) * b);
  return T(1) / (b * b) - T(4) * e / (u * u);
}

/// ln(sinh(a)/a), the antiderivative of L with value 0 at a = 0.
template <typename T>
LODESTONE_HOSTDEV inline T logSinhOverArg(T a) {
  static_assert(std::is_floating_point_v<T>, "floating-point argument expected");
  using std::abs;
  using std::exp;
  using std::log;
  using std::log1p;
  const T b = abs(a);
  if (b < T(1)) {
    const T x = b * b;
    return log1p(x * langevin_series::seriesQ(x));
  }
  if (b > T(1e30)) return b;  // ln(sinh b / b) = b to working precision; also keeps inf finite-safe
  // ln(sinh b / b) = b - ln 2 - ln b + ln(1 - e^{-2b}); ln 2 + ln b, not ln(2b),
  // so that b near the overflow threshold stays finite.
  return b - T(0.69314718055994530942) - log(b) + log1p(-exp(T(-2) * b));
}

/// g = L(a)/a, L'(a) and ln(sinh a / a) together, sharing one exponential:
/// what the Newton Jacobian needs at every Gauss point. Same branches and
/// accuracy as the separate functions.
template <typename T>
struct LangevinTriple {
  T overArg;      ///< L(a)/a
  T derivative;   ///< L'(a)
  T logSinhc;     ///< ln(sinh a / a)
};

template <typename T>
LODESTONE_HOSTDEV inline LangevinTriple<T> langevinTriple(T a) {
  static_assert(std::is_floating_point_v<T>, "floating-point argument expected");
  using std::abs;
  using std::exp;
  using std::log;
  using std::log1p;
  const T b = abs(a);
  LangevinTriple<T> r;
  if (b < T(1)) {
    const T x = b * b;
    const T q = x * langevin_series::seriesQ(x);
    const T sv = langevin_series::seriesS(x);
    r.overArg = langevin_series::seriesP(x) / (T(1) + q);
    r.derivative = sv / (T(1) + x * sv);
    r.logSinhc = log1p(q);
    return r;
  }
  const T e = exp(T(-2) * b);  // in (0, e^-2]; underflows to 0 for large b
  const T u = T(1) - e;        // >= 1 - e^-2: no cancellation
  // Two reciprocals and one logarithm serve all three (this runs at every
  // Gauss point of every evaluation): coth b = (1 + e)/(1 - e) = 1 + 2e/u,
  // and ln(sinh b / b) = b - ln 2 + ln(u / b) with u / b in (0, 1).
  const T ib = T(1) / b, iu = T(1) / u, eu = e * iu;
  r.overArg = (T(1) - ib + T(2) * eu) * ib;
  r.derivative = ib * ib - T(4) * eu * iu;
  r.logSinhc = b > T(1e30) ? b : b - T(0.69314718055994530942) + log(u * ib);
  return r;
}

}  // namespace field
}  // namespace lodestone
