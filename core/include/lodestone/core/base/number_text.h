#pragma once
// Numbers as text for people: the shortest decimal that reads back as the
// same value ("0.4", not "0.40000000000000002"), so a printed number is both
// exact and readable.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace lodestone {
inline namespace base {

/// The fewest significant digits (1..17) with which printf's %g of `v`
/// reads back (strtod) as `v`.
inline int roundTripDigits(double v) {
  char text[40];
  for (int digits = 1; digits < 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, v);
    if (std::strtod(text, nullptr) == v) return digits;
  }
  return 17;
}

/// The same for a float (1..9 digits, read back with strtof).
inline int roundTripDigits(float v) {
  char text[40];
  for (int digits = 1; digits < 9; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, double(v));
    if (std::strtof(text, nullptr) == v) return digits;
  }
  return 9;
}

/// `v` as %g with roundTripDigits(v) digits ("0.4", "5e-05", "1.09e-19");
/// a whole number below 1e17 in plain digits ("1000000"). "nan", "inf".
inline std::string numberText(double v) {
  char text[40];
  const int digits = v == std::floor(v) && std::fabs(v) < 1e17 ? 17 : roundTripDigits(v);
  std::snprintf(text, sizeof text, "%.*g", digits, v);
  return text;
}

/// `v` to at most `digits` significant digits, fewer where fewer read back
/// as `v` (6: "0.4", "3.30698e-05", "82688.5"): for derived quantities in
/// summaries, where the last digits say nothing.
inline std::string numberText(double v, int digits) {
  char text[40];
  std::snprintf(text, sizeof text, "%.*g", std::min(digits, roundTripDigits(v)), v);
  return text;
}

/// The same for a float: the shortest text that strtof reads back as `v`.
inline std::string numberText(float v) {
  char text[40];
  const int digits = v == std::floor(v) && std::fabs(v) < 1e17f ? 17 : roundTripDigits(v);
  std::snprintf(text, sizeof text, "%.*g", digits, double(v));
  return text;
}

}  // namespace base
}  // namespace lodestone
