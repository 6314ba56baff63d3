#include "lodestone/core/base/cpu_features.h"

namespace lodestone {
inline namespace base {

bool cpuHasAvx2Fma() {
#if defined(LODESTONE_X86_AVX2)
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }();
  return has;
#else
  return false;
#endif
}

}  // namespace base
}  // namespace lodestone
