#pragma once
// Deterministic parallel reductions: the same sums (and the same first
// index), bit for bit, whatever the number of threads. tbb::parallel_deterministic_reduce splits the range the
// same way every time (fixed grain, simple partitioner) and joins the partial
// sums in a fixed tree order.
#include <algorithm>
#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

namespace lodestone {
inline namespace base {

constexpr std::size_t kReduceGrain = 4096;

/// fn(m) for every m in [0, count), in parallel chunks of at least `grain`
/// (each index once: loops that write disjoint outputs).
template <typename Fn>
void parallelForEach(std::size_t count, const Fn& fn, std::size_t grain = std::size_t(1) << 13) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, grain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t m = r.begin(); m != r.end(); ++m) fn(m);
  });
}

/// sum_{n in [0,count)} term(n), deterministic.
template <typename T, typename Term>
T deterministicSum(std::size_t count, const Term& term, std::size_t grain = kReduceGrain) {
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, count, grain), T{},
      [&](const tbb::blocked_range<std::size_t>& r, T acc) {
        for (std::size_t n = r.begin(); n != r.end(); ++n) acc += term(n);
        return acc;
      },
      [](T a, const T& b) { return a += b; });
}

/// The first index m in [0, n) for which pred(m) holds, or n: the same index
/// whatever the thread count (a chunk stops at its first hit, or at a lower
/// hit another chunk already found).
template <typename Pred>
std::size_t firstIndexWhere(std::size_t n, const Pred& pred, std::size_t grain = kReduceGrain) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, grain), n,
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t found) {
        for (std::size_t m = r.begin(); m != r.end() && m < found; ++m)
          if (pred(m)) return m;
        return found;
      },
      [](std::size_t a, std::size_t b) { return std::min(a, b); });
}

/// Dot product of two arrays, deterministic.
inline double deterministicDot(const double* a, const double* b, std::size_t count) {
  return deterministicSum<double>(count, [&](std::size_t n) { return a[n] * b[n]; });
}

}  // namespace base
}  // namespace lodestone
