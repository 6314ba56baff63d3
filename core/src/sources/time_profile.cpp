#include "lodestone/core/sources/time_profile.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace sources {

TimeProfile TimeProfile::constant(double value) {
  require(std::isfinite(value), "time profile: constant factor must be finite, got ", value);
  TimeProfile p;
  p.a_ = value;
  return p;
}

TimeProfile TimeProfile::ramp(double t0, double t1, double from, double to) {
  require(std::isfinite(t0), "time profile: ramp start time t0 must be finite (s), got ", t0);
  require(std::isfinite(t1), "time profile: ramp end time t1 must be finite (s), got ", t1);
  require(t1 >= t0, "time profile: ramp end time t1 = ", t1, " s precedes start time t0 = ", t0,
          " s");
  require(std::isfinite(from), "time profile: ramp start value must be finite, got ", from);
  require(std::isfinite(to), "time profile: ramp end value must be finite, got ", to);
  TimeProfile p;
  p.kind_ = Kind::Ramp;
  p.a_ = t0;
  p.b_ = t1;
  p.c_ = from;
  p.d_ = to;
  return p;
}

TimeProfile TimeProfile::sine(double amplitude, double frequency, double phase, double offset) {
  require(std::isfinite(amplitude), "time profile: sine amplitude must be finite, got ", amplitude);
  require(std::isfinite(frequency) && frequency >= 0,
          "time profile: sine frequency must be finite and >= 0 (Hz), got ", frequency);
  require(std::isfinite(phase), "time profile: sine phase must be finite (rad), got ", phase);
  require(std::isfinite(offset), "time profile: sine offset must be finite, got ", offset);
  TimeProfile p;
  p.kind_ = Kind::Sine;
  p.a_ = amplitude;
  p.b_ = frequency;
  p.c_ = phase;
  p.d_ = offset;
  return p;
}

TimeProfile TimeProfile::keyframes(std::vector<double> times, std::vector<double> values) {
  require(!times.empty(), "time profile: keyframes need at least one (time, value) pair");
  require(times.size() == values.size(), "time profile: ", times.size(), " keyframe times but ",
          values.size(), " values");
  for (std::size_t i = 0; i < times.size(); ++i) {
    require(std::isfinite(times[i]), "time profile: keyframe time [", i,
            "] must be finite (s), got ", times[i]);
    require(std::isfinite(values[i]), "time profile: keyframe value [", i, "] must be finite, got ",
            values[i]);
    require(i == 0 || times[i] > times[i - 1],
            "time profile: keyframe times must increase "
            "strictly, but time [",
            i, "] = ", times[i], " s follows ", times[i > 0 ? i - 1 : 0], " s");
  }
  TimeProfile p;
  p.kind_ = Kind::Keyframes;
  p.times_ = std::move(times);
  p.values_ = std::move(values);
  return p;
}

double TimeProfile::operator()(double t) const {
  switch (kind_) {
    case Kind::Constant:
      return a_;
    case Kind::Ramp: {
      if (t >= b_) return d_;  // also the step of a zero-length ramp
      if (t <= a_) return c_;
      const double u = (t - a_) / (b_ - a_);
      return c_ + (d_ - c_) * u;
    }
    case Kind::Sine:
      return d_ + a_ * std::sin(2.0 * kPi * b_ * t + c_);
    case Kind::Keyframes: {
      if (std::isnan(t)) return t;
      if (t <= times_.front()) return values_.front();
      if (t >= times_.back()) return values_.back();
      // First keyframe strictly after t; t lies in [times[i-1], times[i]).
      const std::size_t i = static_cast<std::size_t>(
          std::upper_bound(times_.begin(), times_.end(), t) - times_.begin());
      const double u = (t - times_[i - 1]) / (times_[i] - times_[i - 1]);
      return values_[i - 1] + (values_[i] - values_[i - 1]) * u;
    }
  }
  return a_;
}

std::string TimeProfile::describe() const {
  switch (kind_) {
    case Kind::Constant:
      return concat("constant ", a_);
    case Kind::Ramp:
      return concat("ramp ", c_, " -> ", d_, " over t = [", a_, ", ", b_, "] s");
    case Kind::Sine:
      return concat(d_, " + ", a_, " sin(2 pi ", b_, " Hz t + ", c_, " rad)");
    case Kind::Keyframes: {
      std::string s = concat("keyframes (", times_.size(), "):");
      for (std::size_t i = 0; i < times_.size(); ++i)
        s += concat(" (", times_[i], " s, ", values_[i], ")");
      return s;
    }
  }
  return "unknown";
}

}  // namespace sources
}  // namespace lodestone
