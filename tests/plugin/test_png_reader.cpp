// readPng reads back what writePng writes, pixel for pixel; rows stored
// with each of the five filters (encoded here by hand) decode to the same
// pixels; a file that is not PNG, damaged (CRC) or truncated is refused
// with a message naming it.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/output/atomic_file.h"
#include "lodestone/plugin/output/png_reader.h"
#include "lodestone/plugin/output/png_writer.h"

namespace fs = std::filesystem;
using namespace lodestone;
using namespace lodestone::output;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("lodestone_png_reader_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

std::vector<std::uint8_t> pattern(int w, int h) {
  std::vector<std::uint8_t> rgb(std::size_t(w * h * 3));
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = std::uint8_t((i * 37 + i / 7 * 11) % 256);
  return rgb;
}

void putU32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(std::uint8_t(v >> s));
}

void putChunk(std::vector<std::uint8_t>& out, const char* type, const std::vector<std::uint8_t>& data) {
  putU32(out, std::uint32_t(data.size()));
  std::vector<std::uint8_t> body(type, type + 4);
  body.insert(body.end(), data.begin(), data.end());
  out.insert(out.end(), body.begin(), body.end());
  putU32(out, std::uint32_t(crc32(0L, body.data(), uInt(body.size()))));
}

int paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
}

// A PNG whose row y uses filter y % 5 (PNG spec, section 9).
std::vector<std::uint8_t> filteredPng(int w, int h, const std::vector<std::uint8_t>& rgb) {
  const std::size_t stride = std::size_t(w) * 3;
  std::vector<std::uint8_t> raw;
  for (int y = 0; y < h; ++y) {
    const int filter = y % 5;
    raw.push_back(std::uint8_t(filter));
    const std::uint8_t* row = &rgb[std::size_t(y) * stride];
    const std::uint8_t* up = y > 0 ? row - stride : nullptr;
    for (std::size_t x = 0; x < stride; ++x) {
      const int a = x >= 3 ? row[x - 3] : 0, b = up ? up[x] : 0, c = (up && x >= 3) ? up[x - 3] : 0;
      const int pred = filter == 0 ? 0 : filter == 1 ? a : filter == 2 ? b : filter == 3 ? (a + b) / 2 : paeth(a, b, c);
      raw.push_back(std::uint8_t(row[x] - pred));
    }
  }
  std::vector<std::uint8_t> z(compressBound(uLong(raw.size())));
  uLongf zs = uLongf(z.size());
  EXPECT_EQ(compress(z.data(), &zs, raw.data(), uLong(raw.size())), Z_OK);
  z.resize(zs);
  std::vector<std::uint8_t> png = {137, 80, 78, 71, 13, 10, 26, 10};
  std::vector<std::uint8_t> ihdr;
  putU32(ihdr, std::uint32_t(w));
  putU32(ihdr, std::uint32_t(h));
  ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});
  putChunk(png, "IHDR", ihdr);
  putChunk(png, "IDAT", z);
  putChunk(png, "IEND", {});
  return png;
}

std::string errorOf(const fs::path& p) {
  try {
    readPng(p.string());
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(PngReader, ReadsWhatWritePngWrites) {
  const int w = 37, h = 23;
  const std::vector<std::uint8_t> rgb = pattern(w, h);
  const fs::path p = scratch("round_trip.png");
  writePng(p.string(), w, h, rgb.data());
  const RgbImage image = readPng(p.string());
  EXPECT_EQ(image.width, w);
  EXPECT_EQ(image.height, h);
  EXPECT_EQ(image.rgb, rgb);
}

TEST(PngReader, DecodesEveryRowFilter) {
  const int w = 11, h = 10;
  const std::vector<std::uint8_t> rgb = pattern(w, h);
  const fs::path p = scratch("filters.png");
  writeFileAtomically(p.string(), filteredPng(w, h, rgb));
  EXPECT_EQ(readPng(p.string()).rgb, rgb);
}

TEST(PngReader, RefusesWhatIsNotAWholePng) {
  const fs::path text = scratch("text.png");
  writeFileAtomically(text.string(), std::string("not an image"));
  EXPECT_NE(errorOf(text).find(text.string() + "': not a PNG file"), std::string::npos);
  std::vector<std::uint8_t> png = encodePng(4, 4, pattern(4, 4).data());
  const fs::path cut = scratch("cut.png");
  writeFileAtomically(cut.string(), std::vector<std::uint8_t>(png.begin(), png.end() - 20));
  EXPECT_NE(errorOf(cut).find("truncated"), std::string::npos);
  png[40] ^= 0xff;  // inside IDAT
  const fs::path damaged = scratch("damaged.png");
  writeFileAtomically(damaged.string(), png);
  EXPECT_NE(errorOf(damaged).find("CRC mismatch"), std::string::npos);
  EXPECT_NE(errorOf(scratch("missing.png")).find("cannot open"), std::string::npos);
}

}  // namespace
