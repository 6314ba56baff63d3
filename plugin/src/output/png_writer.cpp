#include "lodestone/plugin/output/png_writer.h"

#include <zlib.h>

#include "lodestone/plugin/output/atomic_file.h"
#include "lodestone/core/base/error.h"

namespace lodestone::output {
namespace {

constexpr int kMaxSide = 1 << 24;

void putU32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  out.push_back(std::uint8_t(v >> 24));
  out.push_back(std::uint8_t(v >> 16));
  out.push_back(std::uint8_t(v >> 8));
  out.push_back(std::uint8_t(v));
}

// Appends one chunk: big-endian length, 4-byte type, data, CRC-32 of type + data.
void putChunk(std::vector<std::uint8_t>& out, const char type[4], const std::uint8_t* data, std::size_t size,
              const std::string& what) {
  if (size > 0x7fffffffu) throw Error(concat(what, ": PNG chunk of ", size, " bytes is too large"));
  putU32(out, std::uint32_t(size));
  const std::size_t typeAt = out.size();
  out.insert(out.end(), type, type + 4);
  if (size > 0) out.insert(out.end(), data, data + size);
  // crc32 takes a uInt length; chunks are below 2^31 bytes, so one call suffices.
  const uLong crc = crc32(crc32(0L, Z_NULL, 0), out.data() + typeAt, uInt(4 + size));
  putU32(out, std::uint32_t(crc));
}

}  // namespace

std::vector<std::uint8_t> encodePng(int width, int height, const std::uint8_t* rgb, const std::string& what) {
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    throw Error(concat(what, ": image size must be 1..", kMaxSide, " pixels per side, got ", width, " x ", height));
  if (rgb == nullptr) throw Error(concat(what, ": no pixel data (null pointer)"));

  // Raw scanlines: a filter-type byte (0 = None) before each row of RGB bytes.
  const std::size_t rowBytes = 3 * std::size_t(width);
  std::vector<std::uint8_t> raw;
  raw.reserve((rowBytes + 1) * std::size_t(height));
  for (int y = 0; y < height; ++y) {
    raw.push_back(0);
    const std::uint8_t* row = rgb + rowBytes * std::size_t(y);
    raw.insert(raw.end(), row, row + rowBytes);
  }
  if (raw.size() > 0x7fffffffu) throw Error(concat(what, ": image of ", width, " x ", height, " pixels is too large"));

  uLongf packedSize = compressBound(uLong(raw.size()));
  std::vector<std::uint8_t> packed(packedSize);
  const int rc = compress2(packed.data(), &packedSize, raw.data(), uLong(raw.size()), Z_BEST_COMPRESSION);
  if (rc != Z_OK) throw Error(concat(what, ": zlib compression failed (code ", rc, ")"));
  packed.resize(packedSize);

  std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<std::uint8_t> ihdr;
  putU32(ihdr, std::uint32_t(width));
  putU32(ihdr, std::uint32_t(height));
  ihdr.push_back(8);  // bit depth
  ihdr.push_back(2);  // colour type: truecolour RGB
  ihdr.push_back(0);  // compression: deflate
  ihdr.push_back(0);  // filter method 0
  ihdr.push_back(0);  // no interlace
  putChunk(png, "IHDR", ihdr.data(), ihdr.size(), what);
  putChunk(png, "IDAT", packed.data(), packed.size(), what);
  putChunk(png, "IEND", nullptr, 0, what);
  return png;
}

void writePng(const std::string& path, int width, int height, const std::uint8_t* rgb) {
  // Temporary file then rename (atomic_file.h): an interrupted run never
  // leaves a truncated preview in place of a complete earlier one.
  writeFileAtomically(path, encodePng(width, height, rgb, path));
}

}  // namespace lodestone::output
