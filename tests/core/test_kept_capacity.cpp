// Kept storage (base/kept_capacity.h): arrays keep their storage from call to
// call, grow with an eighth of room, and new storage of several MiB is
// advised for the system's 2 MiB pages before it is written. The advice is
// checked where the system shows it: the "THPeligible" flag of the memory
// region in /proc/self/smaps, set for advised memory when transparent huge
// pages are in "madvise" mode (Debian's default), and not set when the
// environment turns the advice off (LODESTONE_HUGE_PAGES=off, a second run).
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "lodestone/core/base/kept_capacity.h"

using namespace lodestone;

namespace {

/// The bracketed mode of /sys/kernel/mm/transparent_hugepage/enabled
/// ("always", "madvise", "never"), or "" where the system has none.
std::string hugePageMode() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  std::getline(in, line);
  const std::size_t a = line.find('['), b = line.find(']');
  return a == std::string::npos || b == std::string::npos || b < a ? std::string() : line.substr(a + 1, b - a - 1);
}

/// The value of `field` (e.g. "THPeligible") of the memory region holding
/// address p in /proc/self/smaps, -1 where it is not listed.
long smapsField(const void* p, const std::string& field) {
  std::ifstream in("/proc/self/smaps");
  const std::uintptr_t a = reinterpret_cast<std::uintptr_t>(p);
  std::string line;
  bool inside = false;
  while (std::getline(in, line)) {
    const std::size_t dash = line.find('-');
    if (dash != std::string::npos && dash > 0 && line.find(':') > dash && line.find(' ') > dash) {
      std::uintptr_t lo = 0, hi = 0;
      std::istringstream(line.substr(0, dash)) >> std::hex >> lo;
      std::istringstream(line.substr(dash + 1)) >> std::hex >> hi;
      inside = a >= lo && a < hi;
      continue;
    }
    if (inside && line.compare(0, field.size() + 1, field + ":") == 0) {
      long value = -1;
      std::istringstream(line.substr(field.size() + 1)) >> value;
      return value;
    }
  }
  return -1;
}

long minorFaults() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_minflt;
}

constexpr std::size_t kMiB = std::size_t(1) << 20;

}  // namespace

TEST(KeptCapacity, GrowsWithAnEighthOfRoomAndKeepsStorage) {
  std::vector<double> v;
  resizeKeepingCapacity(v, 800);
  ASSERT_EQ(v.size(), 800u);
  EXPECT_GE(v.capacity(), 900u);
  for (std::size_t m = 0; m < v.size(); ++m) v[m] = double(m);
  const double* storage = v.data();
  resizeKeepingCapacity(v, 880);  // within the room: storage and values kept
  EXPECT_EQ(v.data(), storage);
  EXPECT_EQ(v[799], 799.0);
  EXPECT_EQ(v[879], 0.0);
  resizeKeepingCapacity(v, 100);  // shrinking keeps the storage
  EXPECT_EQ(v.data(), storage);
  EXPECT_EQ(v[99], 99.0);
  resizeKeepingCapacity(v, 5000);  // past the room: new storage, values value-initialised
  ASSERT_EQ(v.size(), 5000u);
  EXPECT_GE(v.capacity(), 5625u);
  EXPECT_EQ(v[99], 0.0);
}

TEST(KeptCapacity, AssignSetsEveryValueInTheKeptStorage) {
  std::vector<int> v;
  assignKeepingCapacity(v, 800, 7);
  ASSERT_EQ(v.size(), 800u);
  EXPECT_GE(v.capacity(), 900u);
  const int* storage = v.data();
  v[3] = 1;
  assignKeepingCapacity(v, 880, -1);  // within the room: the storage kept, every value set
  EXPECT_EQ(v.data(), storage);
  ASSERT_EQ(v.size(), 880u);
  for (int x : v) ASSERT_EQ(x, -1);
}

TEST(KeptCapacity, AdviceNeedsAWholeHugePage) {
  EXPECT_FALSE(adviseHugePages(nullptr, 64 * kMiB));
  std::vector<char> small(kMiB);
  EXPECT_FALSE(adviseHugePages(small.data(), small.size()));  // no whole 2 MiB page inside
}

TEST(KeptCapacity, NewStorageIsAdvisedForHugePages) {
  const std::string mode = hugePageMode();
  if (mode.empty() || mode == "never")
    GTEST_SKIP() << "this system has no transparent huge pages (mode '" << mode << "'): nothing to advise";
  std::vector<double> v;
  const std::size_t n = 64 * kMiB / sizeof(double);
  reserveKeepingCapacity(v, n);
  const double* middle = v.data() + n / 2;  // inside the advised, 2 MiB-aligned part
  if (!hugePageAdviceEnabled()) {
    // LODESTONE_HUGE_PAGES=off: no advice taken, none given.
    EXPECT_FALSE(adviseHugePages(v.data(), v.capacity() * sizeof(double)));
    if (mode == "madvise") {
      EXPECT_EQ(smapsField(middle, "THPeligible"), 0);
    }
    return;
  }
  ASSERT_EQ(smapsField(middle, "THPeligible"), 1) << "mode " << mode << ": the new storage was not advised";
  const long before = minorFaults();
  v.resize(n);  // the first write
  const long faults = minorFaults() - before;
  const long hugeKiB = smapsField(middle, "AnonHugePages");
  // Not asserted: whether the system had free 2 MiB pages at this moment.
  std::printf("64 MiB written in %ld page faults (%ld with 4 KiB pages); %ld KiB of it on huge pages\n", faults,
              long(64 * kMiB / 4096), hugeKiB);
  // Plain storage of the same size is not advised (in "madvise" mode).
  if (mode == "madvise") {
    std::vector<double> plain;
    plain.reserve(n);
    EXPECT_EQ(smapsField(plain.data() + n / 2, "THPeligible"), 0);
  }
}
