#pragma once
// What the CPU running this process can do, for kernels that keep a portable
// build and choose a vector path at run time.

namespace lodestone {
inline namespace base {

/// True on an x86-64 CPU with AVX2 and FMA (checked once); false elsewhere.
bool cpuHasAvx2Fma();

}  // namespace base
}  // namespace lodestone
