#include "lodestone/core/base/kept_capacity.h"

#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>

namespace lodestone {
inline namespace base {

bool hugePageAdviceEnabled() {
  static const bool enabled = [] {
    const char* text = std::getenv(kHugePagesVariable);
    return !(text && (std::strcmp(text, "0") == 0 || std::strcmp(text, "off") == 0));
  }();
  return enabled;
}

bool adviseHugePages(void* data, std::size_t bytes) {
#if defined(MADV_HUGEPAGE)
  if (!hugePageAdviceEnabled()) return false;
  constexpr std::uintptr_t kHuge = std::uintptr_t(2) << 20;  // bytes in one huge page on x86-64 and arm64
  const std::uintptr_t begin = reinterpret_cast<std::uintptr_t>(data);
  if (data == nullptr || bytes < kHuge || begin > UINTPTR_MAX - bytes) return false;
  const std::uintptr_t first = (begin + kHuge - 1) & ~(kHuge - 1);
  const std::uintptr_t last = (begin + bytes) & ~(kHuge - 1);
  if (first >= last) return false;
  return madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE) == 0;
#else
  (void)data;
  (void)bytes;
  return false;
#endif
}

}  // namespace base
}  // namespace lodestone
