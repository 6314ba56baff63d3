#pragma once
// Large zero-initialised arrays whose memory follows what is written: the
// address space of the whole array is reserved up front, a page of it (4 KiB)
// is backed by memory only when first written, and ranges can be handed back
// to the system (they read as zero again). A grid array over a box that the
// material fills only in part costs the pages the material's nodes lie on,
// not the box (the MPM grid, mpm/grid.h).
//
// Reading a page never written costs no memory (the system maps its shared
// zero page). Elements must be trivially copyable and all-zero bytes must be
// their zero value. Linux and other POSIX systems (mmap, madvise). The memory
// held shows in the process's resident set, not counting pages only read.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

namespace lodestone {
inline namespace base {

/// Bytes of reserved address space, backed by memory page by page as written.
class PageMapping {
 public:
  PageMapping() = default;
  /// Reserves `bytes` of zero bytes; throws lodestone::Error (naming the size)
  /// when the system refuses the address space.
  explicit PageMapping(std::size_t bytes);
  PageMapping(PageMapping&& o) noexcept { swap(o); }
  PageMapping& operator=(PageMapping&& o) noexcept {
    PageMapping(std::move(o)).swap(*this);
    return *this;
  }
  PageMapping(const PageMapping&) = delete;
  PageMapping& operator=(const PageMapping&) = delete;
  ~PageMapping();

  void* data() const { return data_; }
  std::size_t bytes() const { return bytes_; }

  /// Makes bytes [offset, offset + length) zero: the whole pages inside go
  /// back to the system, the partial pages at the ends are cleared.
  void zero(std::size_t offset, std::size_t length);
  /// The system's page size, bytes.
  static std::size_t pageSize();

  void swap(PageMapping& o) noexcept {
    std::swap(data_, o.data_);
    std::swap(bytes_, o.bytes_);
  }

 private:
  void* data_ = nullptr;
  std::size_t bytes_ = 0;
};

/// `size` elements of T, all zero at first, over a PageMapping.
template <typename T>
class PageArray {
  static_assert(std::is_trivially_copyable_v<T>, "PageArray: elements must be trivially copyable");

 public:
  PageArray() = default;
  explicit PageArray(std::size_t size) : map_(size * sizeof(T)), size_(size) {}

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T* data() { return static_cast<T*>(map_.data()); }
  const T* data() const { return static_cast<const T*>(map_.data()); }
  T& operator[](std::size_t i) { return data()[i]; }
  const T& operator[](std::size_t i) const { return data()[i]; }
  T* begin() { return data(); }
  T* end() { return data() + size_; }
  const T* begin() const { return data(); }
  const T* end() const { return data() + size_; }

  /// Elements [first, first + count) read zero afterwards; the pages wholly
  /// inside go back to the system.
  void zero(std::size_t first, std::size_t count) { map_.zero(first * sizeof(T), count * sizeof(T)); }
  /// Elements [first, first + count) read zero afterwards, and so does every
  /// page they share with other elements when free(e0, e1) says that those
  /// others, [e0, e1), may be zeroed too: such pages go back to the system
  /// whole instead of being cleared in part.
  template <typename Free>
  void zeroPages(std::size_t first, std::size_t count, const Free& free) {
    if (count == 0) return;
    const std::size_t page = PageMapping::pageSize(), bytes = map_.bytes();
    const std::size_t last = first + count;                      // one past the last element
    const std::size_t b0 = first * sizeof(T), b1 = last * sizeof(T);
    const auto elementsBefore = [&](std::size_t byte) { return std::min(size_, (byte + sizeof(T) - 1) / sizeof(T)); };
    std::size_t z0 = b0, z1 = b1;  // the bytes to zero
    const std::size_t headStart = b0 / page * page, headEnd = std::min(headStart + page, bytes);
    if (headStart < b0 || headEnd > b1) {  // the first page holds other elements
      const bool beforeFree = headStart == b0 || free(headStart / sizeof(T), first);
      const bool afterFree = headEnd <= b1 || free(last, elementsBefore(headEnd));
      if (beforeFree && afterFree) {
        z0 = headStart;
        z1 = std::max(z1, headEnd);
      }
    }
    const std::size_t tailStart = (b1 - 1) / page * page, tailEnd = std::min(tailStart + page, bytes);
    if (tailStart > headStart && tailEnd > b1 && free(last, elementsBefore(tailEnd))) z1 = tailEnd;
    map_.zero(z0, z1 - z0);
  }
  /// All elements zero, no memory held.
  void clear() { map_.zero(0, map_.bytes()); }

 private:
  PageMapping map_;
  std::size_t size_ = 0;
};

}  // namespace base
}  // namespace lodestone
