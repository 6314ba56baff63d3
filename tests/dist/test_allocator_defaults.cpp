// The allocator of a program that starts PETSc (PetscSession, which loads
// SuperLU_DIST and so runs its library constructor, then restores the
// allocator's thresholds: allocator_defaults.h): freed large blocks go back
// to the system, as in a program without PETSc.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <memory>

#include "lodestone/dist/allocator_defaults.h"
#include "lodestone/dist/petsc_session.h"

namespace {

/// Resident memory now, bytes (Linux /proc/self/statm).
double residentBytes() {
  FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return 0;
  long pages = 0, resident = 0;
  const bool ok = std::fscanf(f, "%ld %ld", &pages, &resident) == 2;
  std::fclose(f);
  return ok ? double(resident) * double(sysconf(_SC_PAGESIZE)) : 0;
}

/// Resident bytes handed back when a touched block of `bytes` is freed.
double returnedOnFree(std::size_t bytes) {
  auto block = std::make_unique<char[]>(bytes);
  std::memset(block.get(), 1, bytes);
  const double held = residentBytes();
  block.reset();
  return held - residentBytes();
}

}  // namespace

TEST(AllocatorDefaults, FreedLargeBlocksGoBackToTheSystem) {
  if (residentBytes() <= 0) GTEST_SKIP() << "no /proc/self/statm on this system";
  int argc = 1;
  char name[] = "test_allocator_defaults";
  char* args[] = {name, nullptr};
  char** argv = args;
  const lodestone::dist::PetscSession session(&argc, &argv);
  constexpr std::size_t kBytes = std::size_t(64) << 20;  // 64 MiB
  for (int round = 0; round < 3; ++round) {
    const double returned = returnedOnFree(kBytes);
    EXPECT_GT(returned, 0.9 * double(kBytes)) << "round " << round << ": of a freed 64 MiB block, "
                                              << returned / double(1 << 20) << " MiB went back to the system";
  }
  // Blocks below the mapping threshold, freed from the top of the heap down,
  // go back whenever the free top exceeds the trim threshold: all but less
  // than that threshold of them.
  static_assert(std::size_t(2) << 20 < std::size_t(lodestone::dist::kAllocatorMapThresholdBytes));
  constexpr std::size_t kMany = 96, kEach = std::size_t(2) << 20;  // 96 x 2 MiB
  std::unique_ptr<char[]> blocks[kMany];
  for (auto& b : blocks) {
    b = std::make_unique<char[]>(kEach);
    std::memset(b.get(), 1, kEach);
  }
  const double held = residentBytes();
  for (std::size_t i = kMany; i-- > 0;) blocks[i].reset();
  const double kept = double(lodestone::dist::kAllocatorTrimThresholdBytes);
  EXPECT_GT(held - residentBytes(), 0.9 * (double(kMany * kEach) - kept))
      << "of 192 MiB in 2 MiB blocks freed, " << (held - residentBytes()) / double(1 << 20)
      << " MiB went back to the system";
}
