// Numbers as text: concat and numberText print the shortest decimal that
// reads back as the same value, whole numbers in plain digits, and
// numberText(v, digits) at most `digits` significant digits.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/number_text.h"

using namespace lodestone;

namespace {

TEST(NumberText, ConcatPrintsTheShortestTextThatReadsBack) {
  EXPECT_EQ(concat("CFL ", 0.4, ", dt <= ", 1e-3, " s"), "CFL 0.4, dt <= 0.001 s");
  EXPECT_EQ(concat(5e-05), "5e-05");
  EXPECT_EQ(concat(1.09e-19), "1.09e-19");
  EXPECT_EQ(concat(2.3), "2.3");
  EXPECT_EQ(concat(-0.1), "-0.1");
  EXPECT_EQ(concat(0.1f), "0.1");  // a float as a float, not as the double it widens to
  EXPECT_EQ(concat(1e6), "1000000");  // whole numbers in digits, as before
  EXPECT_EQ(concat(200000.0), "200000");
  EXPECT_EQ(concat(1.5e20), "1.5e+20");
  EXPECT_EQ(concat(0.0), "0");
  EXPECT_EQ(concat(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(concat(std::nan("")), "nan");
  EXPECT_EQ(concat(3, " frames"), "3 frames");  // integers untouched
}

TEST(NumberText, EveryDoubleReadsBackAndNoShorterTextDoes) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> mantissa(-10, 10);
  std::uniform_int_distribution<int> exponent(-30, 30);
  for (int i = 0; i < 20000; ++i) {
    const double v = mantissa(rng) * std::pow(10.0, exponent(rng));
    const std::string text = numberText(v);
    ASSERT_EQ(std::strtod(text.c_str(), nullptr), v) << text;
    const int digits = roundTripDigits(v);
    if (digits > 1) {
      char shorter[40];
      std::snprintf(shorter, sizeof shorter, "%.*g", digits - 1, v);
      ASSERT_NE(std::strtod(shorter, nullptr), v) << text << " vs " << shorter;
    }
    const float f = float(v);
    if (std::isfinite(f)) {
      ASSERT_EQ(std::strtof(numberText(f).c_str(), nullptr), f) << numberText(f);
    }
  }
}

TEST(NumberText, SignificantDigitsForSummaries) {
  EXPECT_EQ(numberText(3.3069819524750075e-05, 6), "3.30698e-05");
  EXPECT_EQ(numberText(82688.514641177375, 6), "82688.5");
  EXPECT_EQ(numberText(0.4, 6), "0.4");
  EXPECT_EQ(numberText(7.5861022606584746e+23, 6), "7.5861e+23");
}

}  // namespace
