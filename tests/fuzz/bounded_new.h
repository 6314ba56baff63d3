#pragma once
// Global operator new/delete for the VDB harnesses (include in exactly one
// translation unit of a harness). OpenVDB allocates whatever sizes a file
// claims (a blosc block of 64 GiB, a metadata string of 4 GiB) before it
// finds the file short. A real process then gets std::bad_alloc, which the
// vdb_io readers turn into InvalidArgument naming the file; under ASan a
// failed throwing new aborts instead, so these replacements throw
// std::bad_alloc above kFuzzAllocationLimit (and when malloc fails), which is
// what the readers must handle. Memory still comes from ASan's malloc, so
// overflows and use-after-free of these blocks are still caught.
#include <cstddef>
#include <cstdlib>
#include <new>

inline constexpr std::size_t kFuzzAllocationLimit = std::size_t(1) << 30;  // 1 GiB

void* operator new(std::size_t size) {
  if (size > kFuzzAllocationLimit) throw std::bad_alloc();
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return ::operator new(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  return size > kFuzzAllocationLimit ? nullptr : std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept { return ::operator new(size, tag); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
