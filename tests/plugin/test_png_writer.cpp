// The examples' PNG writer, checked by decoding its output independently:
// signature, chunk layout and CRCs (zlib's crc32), IHDR fields, and the
// inflated IDAT stream against the image's filter-0 scanlines. Plus the
// colour-map helpers the demo renders with.
#include <gtest/gtest.h>
#include <zlib.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "lodestone/plugin/output/colormap.h"
#include "lodestone/core/base/error.h"
#include "lodestone/plugin/output/png_writer.h"

using namespace lodestone;
using namespace lodestone::output;

namespace {

struct Chunk {
  std::string type;
  std::vector<std::uint8_t> data;
  std::uint32_t crc = 0;
};

std::uint32_t readU32(const std::vector<std::uint8_t>& b, std::size_t at) {
  return (std::uint32_t(b[at]) << 24) | (std::uint32_t(b[at + 1]) << 16) | (std::uint32_t(b[at + 2]) << 8) |
         std::uint32_t(b[at + 3]);
}

// Splits a PNG byte stream into chunks; fails the test on a truncated stream.
std::vector<Chunk> parseChunks(const std::vector<std::uint8_t>& bytes) {
  std::vector<Chunk> chunks;
  std::size_t at = 8;
  while (at < bytes.size()) {
    EXPECT_LE(at + 12, bytes.size()) << "truncated chunk header at byte " << at;
    if (at + 12 > bytes.size()) break;
    const std::uint32_t length = readU32(bytes, at);
    EXPECT_LE(at + 12 + length, bytes.size()) << "truncated chunk at byte " << at;
    if (at + 12 + length > bytes.size()) break;
    Chunk c;
    c.type.assign(bytes.begin() + std::ptrdiff_t(at + 4), bytes.begin() + std::ptrdiff_t(at + 8));
    c.data.assign(bytes.begin() + std::ptrdiff_t(at + 8), bytes.begin() + std::ptrdiff_t(at + 8 + length));
    c.crc = readU32(bytes, at + 8 + length);
    // The CRC covers the type and data bytes.
    const uLong crc = crc32(crc32(0L, Z_NULL, 0), bytes.data() + at + 4, uInt(4 + length));
    EXPECT_EQ(c.crc, std::uint32_t(crc)) << "bad CRC in chunk " << c.type;
    chunks.push_back(std::move(c));
    at += 12 + length;
  }
  return chunks;
}

std::vector<std::uint8_t> readFile(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

std::filesystem::path scratchDir() {
  const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
  auto dir = std::filesystem::temp_directory_path() / ("lodestone_png_test_" + std::to_string(stamp));
  std::filesystem::create_directories(dir);
  return dir;
}

// A deterministic test pattern with all three channels varying.
std::vector<std::uint8_t> pattern(int w, int h) {
  std::vector<std::uint8_t> rgb(std::size_t(3 * w * h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t p = 3 * std::size_t(x + w * y);
      rgb[p] = std::uint8_t(17 * x + 3 * y);
      rgb[p + 1] = std::uint8_t(255 - 11 * y);
      rgb[p + 2] = std::uint8_t((x * y) ^ 0x5a);
    }
  return rgb;
}

void checkDecodes(const std::vector<std::uint8_t>& bytes, int w, int h, const std::vector<std::uint8_t>& rgb) {
  const std::uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  ASSERT_GE(bytes.size(), 8u);
  for (int b = 0; b < 8; ++b) EXPECT_EQ(bytes[std::size_t(b)], signature[b]) << "signature byte " << b;

  const std::vector<Chunk> chunks = parseChunks(bytes);
  ASSERT_GE(chunks.size(), 3u);
  ASSERT_EQ(chunks.front().type, "IHDR");
  EXPECT_EQ(chunks.back().type, "IEND");
  EXPECT_TRUE(chunks.back().data.empty());

  const Chunk& ihdr = chunks.front();
  ASSERT_EQ(ihdr.data.size(), 13u);
  EXPECT_EQ(readU32(ihdr.data, 0), std::uint32_t(w));
  EXPECT_EQ(readU32(ihdr.data, 4), std::uint32_t(h));
  EXPECT_EQ(ihdr.data[8], 8);   // bit depth
  EXPECT_EQ(ihdr.data[9], 2);   // truecolour
  EXPECT_EQ(ihdr.data[10], 0);  // deflate
  EXPECT_EQ(ihdr.data[11], 0);  // filter method
  EXPECT_EQ(ihdr.data[12], 0);  // no interlace

  // IDAT chunks (consecutive) concatenate to one zlib stream.
  std::vector<std::uint8_t> idat;
  for (std::size_t c = 1; c + 1 < chunks.size(); ++c) {
    EXPECT_EQ(chunks[c].type, "IDAT");
    idat.insert(idat.end(), chunks[c].data.begin(), chunks[c].data.end());
  }
  std::vector<std::uint8_t> expected;
  for (int y = 0; y < h; ++y) {
    expected.push_back(0);  // filter type None
    const auto row = rgb.begin() + std::ptrdiff_t(3 * w * y);
    expected.insert(expected.end(), row, row + 3 * w);
  }
  std::vector<std::uint8_t> inflated(expected.size() + 64);
  uLongf size = uLongf(inflated.size());
  ASSERT_EQ(uncompress(inflated.data(), &size, idat.data(), uLong(idat.size())), Z_OK);
  inflated.resize(size);
  EXPECT_EQ(inflated, expected);
}

}  // namespace

TEST(PngWriter, FileDecodesToTheImage) {
  const auto dir = scratchDir();
  const int w = 13, h = 7;  // odd sizes: no accidental alignment
  const std::vector<std::uint8_t> rgb = pattern(w, h);
  const auto path = dir / "pattern.png";
  writePng(path.string(), w, h, rgb.data());
  const std::vector<std::uint8_t> bytes = readFile(path);
  checkDecodes(bytes, w, h, rgb);
  EXPECT_EQ(bytes, encodePng(w, h, rgb.data()));
  std::filesystem::remove_all(dir);
}

TEST(PngWriter, SinglePixelAndWideImages) {
  const std::vector<std::uint8_t> one = {1, 2, 3};
  checkDecodes(encodePng(1, 1, one.data()), 1, 1, one);
  const std::vector<std::uint8_t> wide = pattern(700, 3);
  checkDecodes(encodePng(700, 3, wide.data()), 700, 3, wide);
}

TEST(PngWriter, OverwritesAnExistingFile) {
  const auto dir = scratchDir();
  const auto path = dir / "twice.png";
  const std::vector<std::uint8_t> big = pattern(40, 40), small = pattern(2, 2);
  writePng(path.string(), 40, 40, big.data());
  writePng(path.string(), 2, 2, small.data());
  checkDecodes(readFile(path), 2, 2, small);
  std::filesystem::remove_all(dir);
}

TEST(PngWriter, ErrorsNameThePath) {
  const std::vector<std::uint8_t> rgb = pattern(4, 4);
  const std::string missing = (scratchDir() / "no_such_dir" / "x.png").string();
  try {
    writePng(missing, 4, 4, rgb.data());
    FAIL() << "writing into a missing directory did not throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(std::filesystem::path(missing).parent_path().parent_path());
  EXPECT_THROW(writePng("bad_size.png", 0, 4, rgb.data()), Error);
  EXPECT_THROW(writePng("bad_size.png", 4, -1, rgb.data()), Error);
  EXPECT_THROW(writePng("null.png", 4, 4, nullptr), Error);
  EXPECT_FALSE(std::filesystem::exists("bad_size.png"));
  EXPECT_FALSE(std::filesystem::exists("null.png"));
}

// Atomic replacement: the new file is renamed over the old one, so a hard
// link to the old file (a reader holding it) still sees the complete old
// image; writing in place would have truncated and rewritten it. No
// temporary file is left beside the output.
TEST(PngWriter, ReplacesAtomicallyAndLeavesNoTemporaries) {
  const auto dir = scratchDir();
  const auto path = dir / "frame_0001.png";
  const auto reader = dir / "held_by_a_reader.png";
  const std::vector<std::uint8_t> first = pattern(9, 5);
  writePng(path.string(), 9, 5, first.data());
  std::filesystem::create_hard_link(path, reader);
  EXPECT_THROW(writePng(path.string(), 0, 5, first.data()), Error);
  checkDecodes(readFile(path), 9, 5, first);
  const std::vector<std::uint8_t> second = pattern(3, 8);
  writePng(path.string(), 3, 8, second.data());
  checkDecodes(readFile(path), 3, 8, second);
  checkDecodes(readFile(reader), 9, 5, first);
  std::filesystem::remove(reader);
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    ++files;
    EXPECT_EQ(entry.path().filename(), "frame_0001.png") << "left behind: " << entry.path();
  }
  EXPECT_EQ(files, 1);
  std::filesystem::remove_all(dir);
}

TEST(Colormap, EndsAndMonotoneLightness) {
  // Published end colours of matplotlib's maps (0..255), within the fit's error.
  const Rgb v0 = mapColour(Colormap::Viridis, 0), v1 = mapColour(Colormap::Viridis, 1);
  EXPECT_NEAR(v0.r, 68, 4);
  EXPECT_NEAR(v0.g, 1, 4);
  EXPECT_NEAR(v0.b, 84, 4);
  EXPECT_NEAR(v1.r, 253, 4);
  EXPECT_NEAR(v1.g, 231, 4);
  EXPECT_NEAR(v1.b, 37, 4);
  const Rgb i0 = mapColour(Colormap::Inferno, 0), i1 = mapColour(Colormap::Inferno, 1);
  EXPECT_LE(i0.r + i0.g + i0.b, 12);
  EXPECT_NEAR(i1.r, 252, 4);
  EXPECT_NEAR(i1.g, 255, 4);
  EXPECT_NEAR(i1.b, 164, 6);
  // Perceptual maps: luma rises steadily from 0 to 1.
  for (Colormap map : {Colormap::Viridis, Colormap::Inferno}) {
    double previous = -1;
    for (int s = 0; s <= 32; ++s) {
      const Rgb c = mapColour(map, s / 32.0);
      const double luma = 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
      EXPECT_GT(luma, previous) << toString(map) << " at t = " << s / 32.0;
      previous = luma;
    }
  }
  // Out of range clamps; NaN is grey.
  EXPECT_EQ(mapColour(Colormap::Viridis, -3).g, v0.g);
  EXPECT_EQ(mapColour(Colormap::Viridis, 7).r, v1.r);
  EXPECT_EQ(mapColour(Colormap::Inferno, std::nan("")).r, 128);
}

TEST(Colormap, RenderOrientationRangeAndOverlays) {
  // Values rise with the row index (z); row 0 is the bottom of the image.
  ScalarSlice s(3, 4);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 3; ++i) s.at(i, j) = std::pow(10.0, j);  // 1, 10, 100, 1000
  RenderOptions ro;
  ro.logScale = true;
  ro.logDecades = 2;
  ro.pixelsPerSample = 4;
  ColourRange range;
  RgbImage img = renderScalar(s, ro, &range);
  EXPECT_EQ(img.width, 9);
  EXPECT_EQ(img.height, 13);
  EXPECT_TRUE(range.log);
  EXPECT_DOUBLE_EQ(range.max, 1000);
  EXPECT_DOUBLE_EQ(range.min, 10);  // 2 decades below the maximum
  const Rgb top = img.get(4, 0), bottom = img.get(4, img.height - 1);
  EXPECT_EQ(top.r, mapColour(Colormap::Viridis, 1).r);
  EXPECT_EQ(bottom.g, mapColour(Colormap::Viridis, 0).g);
  EXPECT_NEAR(range.normalise(100), 0.5, 1e-12);

  // Contour where the values cross 50: between rows 1 and 2, painted just above.
  drawContour(img, s, 4, 50, Rgb{255, 0, 255});
  int painted = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const Rgb c = img.get(x, y);
      if (c.r == 255 && c.g == 0 && c.b == 255) {
        ++painted;
        EXPECT_GE(s.sample(x / 4.0, (img.height - 1 - y) / 4.0), 50);
      }
    }
  EXPECT_EQ(painted, img.width);  // one full row

  appendColourBar(img, Colormap::Viridis, range, 5, 2);
  EXPECT_EQ(img.height, 13 + 2 + 5);
  EXPECT_EQ(img.rgb.size(), std::size_t(3 * img.width * img.height));
  EXPECT_EQ(img.get(img.width - 1, img.height - 1).r, mapColour(Colormap::Viridis, 1).r);
  EXPECT_EQ(img.get(0, img.height - 1).b, mapColour(Colormap::Viridis, 0).b);
}
