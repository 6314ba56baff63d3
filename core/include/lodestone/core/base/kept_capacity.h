#pragma once
// Arrays rebuilt on every call (a field problem's per-cell arrays, a
// stencil's coefficients as the material moves, a solver's node vectors)
// keep their storage from one call to the next: memory touched for the first
// time costs a page fault per 4 KiB, more than the arithmetic of a warm field
// solve. When a count grows past the storage, new storage gets an eighth more
// room, so that a slowly growing count does not allocate anew on every call,
// and storage of several MiB is offered to the system for 2 MiB pages
// (adviseHugePages) before anything is written to it: one fault then maps
// 512 times the memory.
#include <cstddef>
#include <vector>

namespace lodestone {
inline namespace base {

/// The environment variable that turns the advice off: "0" or "off" (read
/// once per process). Where the system's memory is fragmented, a fault on
/// advised memory may wait for the kernel to assemble a huge page.
inline constexpr const char* kHugePagesVariable = "LODESTONE_HUGE_PAGES";
/// False where kHugePagesVariable turns the advice off.
bool hugePageAdviceEnabled();

/// Asks the system to back the whole 2 MiB pages inside bytes [data, data +
/// bytes) with huge pages when they are first written (Linux transparent
/// huge pages, which Debian enables for memory that asks, "madvise" in
/// /sys/kernel/mm/transparent_hugepage/enabled). Advice only: the contents,
/// and the memory's lifetime, are the caller's; where the system has no such
/// pages, the range holds no whole one or the advice is turned off
/// (kHugePagesVariable), nothing changes. Returns whether the system took
/// the advice for at least one page.
bool adviseHugePages(void* data, std::size_t bytes);

/// Makes room for n elements in v: its storage when that holds n;
/// otherwise the old storage is released first (not copied: the contents
/// are discarded) and new storage reserved for n + n/8, advised for huge
/// pages (adviseHugePages).
template <typename T>
void reserveKeepingCapacity(std::vector<T>& v, std::size_t n) {
  if (n <= v.capacity()) return;
  std::vector<T>().swap(v);
  v.reserve(n + n / 8);
  adviseHugePages(v.data(), v.capacity() * sizeof(T));
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

/// v set to n copies of value in v's storage when it holds n
/// (reserveKeepingCapacity). For arrays that start from one value.
template <typename T>
void assignKeepingCapacity(std::vector<T>& v, std::size_t n, const T& value) {
  reserveKeepingCapacity(v, n);
  v.assign(n, value);
}

}  // namespace base
}  // namespace lodestone
