#pragma once
// What the CPU running this process can do, for kernels that keep a portable
// build and choose a vector path at run time, and the one place that
// chooses it.
#include <utility>

/// Defined where the compiler can build a function for AVX2 beside the
/// portable build (GCC or Clang on x86-64): kernels written with intrinsics
/// test it; kernels written once go through runWidest below.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define LODESTONE_X86_AVX2 1
#endif

namespace lodestone {
inline namespace base {

/// True on an x86-64 CPU with AVX2 and FMA (checked once); false elsewhere.
bool cpuHasAvx2Fma();

/// Whether runWidest's AVX2 variant may fuse a multiply and an add into one
/// FMA where the expression allows. Allowed: it rounds once where the
/// portable variant rounds twice, so machines with and without AVX2 differ
/// in the last digits (one machine still gives the same bits run after run).
/// Forbidden: both variants give the same bits.
enum class FusedMultiplyAdd { Allowed, Forbidden };

namespace cpu_dispatch_detail {
#if defined(LODESTONE_X86_AVX2)
template <typename Kernel, typename... Args>
__attribute__((target("avx2,fma"))) void avx2Fma(const Kernel& kernel, Args&&... args) {
  kernel(std::forward<Args>(args)...);
}
template <typename Kernel, typename... Args>
__attribute__((target("avx2"))) void avx2(const Kernel& kernel, Args&&... args) {
  kernel(std::forward<Args>(args)...);
}
#endif
template <typename Kernel, typename... Args>
void portable(const Kernel& kernel, Args&&... args) {
  kernel(std::forward<Args>(args)...);
}
}  // namespace cpu_dispatch_detail

/// kernel(args...) in the widest variant the CPU runs: AVX2 (with FMA as
/// `fma` says) where cpuHasAvx2Fma(), else the portable build. The kernel's
/// call operator must be always_inline, so that each variant compiles it
/// for its own instruction set.
template <FusedMultiplyAdd fma, typename Kernel, typename... Args>
void runWidest(const Kernel& kernel, Args&&... args) {
#if defined(LODESTONE_X86_AVX2)
  if (cpuHasAvx2Fma()) {
    if constexpr (fma == FusedMultiplyAdd::Allowed)
      cpu_dispatch_detail::avx2Fma(kernel, std::forward<Args>(args)...);
    else
      cpu_dispatch_detail::avx2(kernel, std::forward<Args>(args)...);
    return;
  }
#endif
  cpu_dispatch_detail::portable(kernel, std::forward<Args>(args)...);
}

}  // namespace base
}  // namespace lodestone
