#include "lodestone/plugin/output/png_reader.h"

#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <vector>

#include "lodestone/core/base/error.h"

namespace lodestone::output {
namespace {

std::uint32_t getU32(const std::uint8_t* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | std::uint32_t(p[3]);
}

int paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
}

}  // namespace

RgbImage readPng(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InvalidArgument(concat("cannot open '", path, "'"));
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const auto bad = [&](const std::string& why) { return InvalidArgument(concat("'", path, "': ", why)); };
  static const std::uint8_t kSignature[8] = {137, 80, 78, 71, 13, 10, 26, 10};
  if (bytes.size() < 8 || !std::equal(kSignature, kSignature + 8, bytes.begin())) throw bad("not a PNG file");
  std::size_t at = 8;
  int width = 0, height = 0;
  std::vector<std::uint8_t> idat;
  bool end = false;
  while (!end) {
    if (at + 12 > bytes.size()) throw bad("truncated (no IEND chunk)");
    const std::uint32_t size = getU32(&bytes[at]);
    if (size > bytes.size() - at - 12) throw bad("truncated chunk");
    const std::uint8_t* type = &bytes[at + 4];
    const std::uint8_t* data = type + 4;
    const uLong crc = crc32(crc32(0L, Z_NULL, 0), type, uInt(4 + size));
    if (std::uint32_t(crc) != getU32(data + size)) throw bad("chunk CRC mismatch (damaged file)");
    const std::string name(reinterpret_cast<const char*>(type), 4);
    if (name == "IHDR") {
      if (size != 13) throw bad("bad IHDR chunk");
      width = int(getU32(data));
      height = int(getU32(data + 4));
      if (data[8] != 8 || data[9] != 2 || data[12] != 0)
        throw bad(concat("bit depth ", int(data[8]), ", colour type ", int(data[9]), ", interlace ", int(data[12]),
                         ": only 8-bit RGB without interlace is read"));
      if (width <= 0 || height <= 0 || width > (1 << 24) || height > (1 << 24)) throw bad("bad image size");
    } else if (name == "IDAT") {
      idat.insert(idat.end(), data, data + size);
    } else if (name == "IEND") {
      end = true;
    }
    at += 12 + size;
  }
  if (width == 0) throw bad("no IHDR chunk");
  const std::size_t stride = std::size_t(width) * 3;
  std::vector<std::uint8_t> raw((stride + 1) * std::size_t(height));
  uLongf rawSize = uLongf(raw.size());
  if (uncompress(raw.data(), &rawSize, idat.data(), uLong(idat.size())) != Z_OK || rawSize != raw.size())
    throw bad("image data does not inflate to the image's size");
  RgbImage image;
  image.width = width;
  image.height = height;
  image.rgb.resize(stride * std::size_t(height));
  for (int y = 0; y < height; ++y) {
    const std::uint8_t filter = raw[std::size_t(y) * (stride + 1)];
    const std::uint8_t* src = &raw[std::size_t(y) * (stride + 1) + 1];
    std::uint8_t* row = &image.rgb[std::size_t(y) * stride];
    const std::uint8_t* up = y > 0 ? row - stride : nullptr;
    for (std::size_t x = 0; x < stride; ++x) {
      const int a = x >= 3 ? row[x - 3] : 0, b = up ? up[x] : 0, c = (up && x >= 3) ? up[x - 3] : 0;
      int predictor = 0;
      switch (filter) {
        case 0: predictor = 0; break;
        case 1: predictor = a; break;
        case 2: predictor = b; break;
        case 3: predictor = (a + b) / 2; break;
        case 4: predictor = paeth(a, b, c); break;
        default: throw bad(concat("row ", y, " has filter type ", int(filter), " (0..4 exist)"));
      }
      row[x] = std::uint8_t(src[x] + predictor);
    }
  }
  return image;
}

}  // namespace lodestone::output
