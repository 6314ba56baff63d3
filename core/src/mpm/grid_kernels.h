#pragma once
// What the MPM grid's source files share (grid.cpp, grid_binning.cpp,
// grid_storage.cpp): the instruction-set dispatch of their kernels, their
// parallel reduction and the binning's limit.
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <cstddef>
#include <cstdint>
#include <utility>

#include "lodestone/core/base/cpu_features.h"
#include "lodestone/core/mpm/grid.h"

namespace lodestone {
inline namespace mpm {

namespace {

// The kernels below (DepositKernel, G2PKernel, BinKernel, SpeedKernel) run
// in the widest variant the CPU has (runWidest, base/cpu_features.h), FMA
// allowed: a machine gives the same bits run after run and for any thread
// count, and machines with and without AVX2 differ in the last digits.
template <typename Kernel, typename... Args>
void runKernel(const Kernel& kernel, Args&&... args) {
  runWidest<FusedMultiplyAdd::Allowed>(kernel, std::forward<Args>(args)...);
}

/// kernel(begin, end, acc) over [0, count) in chunks of `grain`, each
/// chunk's Sums joined (Sums::join; min, max and counts: order-free).
template <typename Sums, typename Kernel>
Sums reduceKernel(const Kernel& kernel, std::size_t count, std::size_t grain) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, count, grain), Sums{},
      [&](const tbb::blocked_range<std::size_t>& r, Sums acc) {
        runKernel(kernel, r.begin(), r.end(), acc);
        return acc;
      },
      [](Sums a, const Sums& b) {
        a.join(b);
        return a;
      });
}

constexpr std::uint32_t kBadKey = std::uint32_t(kMpmGridCountLimit);

}  // namespace

}  // namespace mpm
}  // namespace lodestone
