#pragma once
// Arrays rebuilt on every call (a field problem's per-cell arrays, a
// stencil's coefficients as the material moves) keep their storage from one
// call to the next: memory touched for the first time costs a page fault
// per 4 KiB, more than the arithmetic of a warm field solve. When a count
// grows past the storage, new storage gets an eighth more room, so that a
// slowly growing count does not allocate anew on every call.
#include <cstddef>
#include <vector>

namespace lodestone {
inline namespace base {

/// Makes room for n elements in v: its storage when that holds n;
/// otherwise the old storage is released first (not copied: the contents
/// are discarded) and new storage reserved for n + n/8.
template <typename T>
void reserveKeepingCapacity(std::vector<T>& v, std::size_t n) {
  if (n <= v.capacity()) return;
  std::vector<T>().swap(v);
  v.reserve(n + n / 8);
}

/// v resized to n elements in v's storage when it holds n
/// (reserveKeepingCapacity): elements below the old size keep their values
/// when the storage is kept, new ones are value-initialized. For arrays
/// that the caller overwrites whole.
template <typename T>
void resizeKeepingCapacity(std::vector<T>& v, std::size_t n) {
  reserveKeepingCapacity(v, n);
  v.resize(n);
}

}  // namespace base
}  // namespace lodestone
