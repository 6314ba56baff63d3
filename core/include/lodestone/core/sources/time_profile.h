#pragma once
// A dimensionless factor s(t) that scales an applied-field source in time
// (t in s): a constant, a linear ramp, a sinusoid, or piecewise-linear
// keyframes. A small copyable value; factories validate their arguments and
// throw InvalidArgument naming the bad value and its unit.
#include <string>
#include <vector>

namespace lodestone {
inline namespace sources {

class TimeProfile {
 public:
  enum class Kind { Constant, Ramp, Sine, Keyframes };

  /// s(t) = 1.
  TimeProfile() = default;

  /// s(t) = value (finite).
  static TimeProfile constant(double value = 1.0);

  /// Linear ramp: s = from for t <= t0, s = to for t >= t1, linear in between.
  /// Times in s, finite, t1 >= t0; t1 == t0 is a step at t0 (s(t0) = to).
  static TimeProfile ramp(double t0, double t1, double from = 0.0, double to = 1.0);

  /// s(t) = offset + amplitude * sin(2 pi frequency t + phase); frequency in Hz
  /// (finite, >= 0), phase in rad.
  static TimeProfile sine(double amplitude, double frequency, double phase = 0.0,
                          double offset = 0.0);

  /// Piecewise-linear through (times[i] s, values[i]); held constant before the
  /// first and after the last keyframe. At least one keyframe, times strictly
  /// increasing, everything finite, both vectors the same length.
  static TimeProfile keyframes(std::vector<double> times, std::vector<double> values);

  /// s(t) for finite t (s). A NaN t gives NaN for every kind but Constant.
  double operator()(double t) const;

  Kind kind() const { return kind_; }
  /// True for Kind::Constant (the factor never changes).
  bool isConstant() const { return kind_ == Kind::Constant; }

  /// One line, e.g. "ramp 0 -> 1 over t = [0, 0.5] s".
  std::string describe() const;

 private:
  Kind kind_ = Kind::Constant;
  // Constant: a = value. Ramp: a = t0, b = t1, c = from, d = to.
  // Sine: a = amplitude, b = frequency, c = phase, d = offset.
  double a_ = 1.0, b_ = 0.0, c_ = 0.0, d_ = 0.0;
  std::vector<double> times_, values_;  // Keyframes only
};

}  // namespace sources
}  // namespace lodestone
