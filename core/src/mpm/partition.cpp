#include "lodestone/core/mpm/partition.h"

#include <algorithm>
#include <cstring>

namespace lodestone {
inline namespace mpm {

double keyAsDouble(std::uint64_t key) {
  double value = 0;
  std::memcpy(&value, &key, sizeof value);
  return value;
}

std::uint64_t keyOf(double value) {
  std::uint64_t key = 0;
  std::memcpy(&key, &value, sizeof key);
  return key;
}

std::vector<double> allGatherByKey(MpmPartition& partition, const std::vector<double>& local, std::size_t width) {
  const std::vector<double> all = partition.allGather(local);
  const std::size_t n = all.size() / width;
  std::vector<std::size_t> order(n);
  for (std::size_t q = 0; q < n; ++q) order[q] = q;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return keyOf(all[a * width]) < keyOf(all[b * width]); });
  std::vector<double> sorted(all.size());
  for (std::size_t q = 0; q < n; ++q)
    std::copy_n(all.begin() + std::ptrdiff_t(order[q] * width), width, sorted.begin() + std::ptrdiff_t(q * width));
  return sorted;
}

}  // namespace mpm
}  // namespace lodestone
