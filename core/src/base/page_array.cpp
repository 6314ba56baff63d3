#include "lodestone/core/base/page_array.h"

#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace base {

std::size_t PageMapping::pageSize() {
  static const std::size_t size = std::size_t(sysconf(_SC_PAGESIZE));
  return size;
}

PageMapping::PageMapping(std::size_t bytes) {
  if (bytes == 0) return;
  // MAP_NORESERVE: the address space is not charged against the commit limit
  // up front; memory is taken page by page as the array is written.
  void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED)
    throw Error(concat("cannot reserve ", bytes, " bytes (", double(bytes) / double(1u << 30),
                       " GiB) of address space for a grid array: ", std::strerror(errno)));
  data_ = p;
  bytes_ = bytes;
}

PageMapping::~PageMapping() {
  if (data_) munmap(data_, bytes_);
}

void PageMapping::zero(std::size_t offset, std::size_t length) {
  if (length == 0) return;
  require(offset <= bytes_ && length <= bytes_ - offset, "PageMapping::zero: bytes [", offset, ", ", offset + length,
          ") outside the mapping of ", bytes_, " bytes");
  char* base = static_cast<char*>(data_);
  const std::size_t page = pageSize();
  const std::size_t first = (offset + page - 1) / page * page;  // first whole page
  const std::size_t last = (offset + length) / page * page;     // end of the last whole page
  if (first >= last) {
    std::memset(base + offset, 0, length);
    return;
  }
  std::memset(base + offset, 0, first - offset);
  std::memset(base + last, 0, offset + length - last);
  // Private anonymous pages read as zero after MADV_DONTNEED.
  if (madvise(base + first, last - first, MADV_DONTNEED) != 0) std::memset(base + first, 0, last - first);
}

}  // namespace base
}  // namespace lodestone
