#include "lodestone/dist/allocator_defaults.h"

#include <cstdlib>  // defines __GLIBC__ with glibc
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace lodestone {
inline namespace dist {

void restoreAllocatorDefaults() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_MAX, 65536);  // glibc's default count of mapped blocks
  mallopt(M_MMAP_THRESHOLD, kAllocatorMapThresholdBytes);
  mallopt(M_TRIM_THRESHOLD, kAllocatorTrimThresholdBytes);
#endif
}

}  // namespace dist
}  // namespace lodestone
