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

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define LODESTONE_MPM_AVX2 1
#endif

namespace lodestone {
inline namespace mpm {

namespace {

// The kernels below (DepositKernel, G2PKernel, BinKernel, SpeedKernel) are
// compiled twice: for any x86-64 CPU and for AVX2 with FMA, chosen at run
// time. The compiler fuses a multiply and an add into one FMA where the
// expression allows, so the AVX2 variant rounds once where the portable one
// rounds twice: a machine gives the same bits run after run and for any
// thread count, and machines with and without AVX2 differ in the last digits.
template <typename Kernel, typename... Args>
void runPortable(const Kernel& kernel, Args&&... args) {
  kernel(std::forward<Args>(args)...);
}

#if defined(LODESTONE_MPM_AVX2)
template <typename Kernel, typename... Args>
__attribute__((target("avx2,fma"))) void runAvx2(const Kernel& kernel, Args&&... args) {
  kernel(std::forward<Args>(args)...);
}
#endif

/// kernel(args...) in the widest variant the CPU runs.
template <typename Kernel, typename... Args>
void runKernel(const Kernel& kernel, Args&&... args) {
#if defined(LODESTONE_MPM_AVX2)
  if (cpuHasAvx2Fma()) {
    runAvx2(kernel, std::forward<Args>(args)...);
    return;
  }
#endif
  runPortable(kernel, std::forward<Args>(args)...);
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
