#pragma once
// Wall-clock timing of the stages that reports break down (seconds).
#include <chrono>

namespace lodestone {
inline namespace base {

using SteadyClock = std::chrono::steady_clock;

/// Seconds of wall time since t0.
inline double secondsSince(SteadyClock::time_point t0) {
  return std::chrono::duration<double>(SteadyClock::now() - t0).count();
}

}  // namespace base
}  // namespace lodestone
