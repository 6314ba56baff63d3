// The PLY point-cloud writer, checked by parsing its output here: the header
// line by line, then every record of the binary body decoded as
// little-endian float / int / uchar and compared with the inputs (rounded to
// float). Plus its argument checks and the atomic write to disk.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/output/ply_writer.h"

using namespace lodestone;
using namespace lodestone::output;

namespace {

struct ParsedPly {
  std::vector<std::string> headerLines;
  std::size_t vertices = 0;
  std::vector<std::pair<std::string, std::string>> properties;  // type, name
  std::vector<std::uint8_t> body;
};

// A small independent PLY reader: header lines up to "end_header\n", then the body.
ParsedPly parsePly(const std::vector<std::uint8_t>& bytes) {
  ParsedPly p;
  std::size_t at = 0;
  while (at < bytes.size()) {
    const std::size_t eol =
        std::size_t(std::find(bytes.begin() + std::ptrdiff_t(at), bytes.end(), '\n') - bytes.begin());
    EXPECT_LT(eol, bytes.size()) << "unterminated header line";
    if (eol >= bytes.size()) break;
    const std::string line(bytes.begin() + std::ptrdiff_t(at), bytes.begin() + std::ptrdiff_t(eol));
    p.headerLines.push_back(line);
    at = eol + 1;
    std::istringstream words(line);
    std::string word;
    words >> word;
    if (word == "element") {
      std::string name;
      words >> name >> p.vertices;
      EXPECT_EQ(name, "vertex");
    } else if (word == "property") {
      std::string type, name;
      words >> type >> name;
      p.properties.emplace_back(type, name);
    } else if (word == "end_header") {
      break;
    }
  }
  p.body.assign(bytes.begin() + std::ptrdiff_t(at), bytes.end());
  return p;
}

std::uint32_t le32(const std::uint8_t* b) {
  return std::uint32_t(b[0]) | (std::uint32_t(b[1]) << 8) | (std::uint32_t(b[2]) << 16) | (std::uint32_t(b[3]) << 24);
}
float leFloat(const std::uint8_t* b) {
  const std::uint32_t u = le32(b);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

std::vector<std::uint8_t> readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<std::uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::filesystem::path freshDir(const std::string& name) {
  // The process id keeps concurrent runs (several build trees) apart.
  const auto dir = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace

TEST(PlyWriter, HeaderAndBodyRoundTrip) {
  const std::vector<Vec3d> x = {{0.1, -0.2, 0.3}, {1e-3, 2.5, -7.0}, {0, 0, 0}};
  const std::vector<Vec3d> v = {{1, 2, 3}, {-0.5, 0.25, 0.125}, {1e-7, -1e7, 0}};
  const std::vector<double> np = {1e9, 2.5e9, 0.0};
  const std::vector<std::int32_t> material = {0, 7, -2};
  const std::vector<Rgb> colours = {{255, 0, 10}, {1, 2, 3}, {0, 128, 255}};

  PlyPointCloud cloud(x);
  cloud.addComment("lodestone frame 12, units: m, m/s");
  cloud.addVec3("vx", "vy", "vz", v);
  cloud.addFloat("n_p", np);
  cloud.addInt("material", material);
  cloud.addColours(colours);
  const ParsedPly p = parsePly(cloud.encode());

  const std::vector<std::string> expectedHeader = {"ply",
                                                   "format binary_little_endian 1.0",
                                                   "comment lodestone frame 12, units: m, m/s",
                                                   "element vertex 3",
                                                   "property float x",
                                                   "property float y",
                                                   "property float z",
                                                   "property float vx",
                                                   "property float vy",
                                                   "property float vz",
                                                   "property float n_p",
                                                   "property int material",
                                                   "property uchar red",
                                                   "property uchar green",
                                                   "property uchar blue",
                                                   "end_header"};
  EXPECT_EQ(p.headerLines, expectedHeader);
  EXPECT_EQ(p.vertices, 3u);

  const std::size_t record = 7 * 4 + 4 + 3;
  ASSERT_EQ(p.body.size(), 3 * record);
  for (std::size_t n = 0; n < 3; ++n) {
    const std::uint8_t* r = p.body.data() + n * record;
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(leFloat(r + 4 * a), float(x[n][a])) << "point " << n << " axis " << a;
      EXPECT_EQ(leFloat(r + 12 + 4 * a), float(v[n][a])) << "point " << n << " axis " << a;
    }
    EXPECT_EQ(leFloat(r + 24), float(np[n]));
    EXPECT_EQ(std::int32_t(le32(r + 28)), material[n]);
    EXPECT_EQ(r[32], colours[n].r);
    EXPECT_EQ(r[33], colours[n].g);
    EXPECT_EQ(r[34], colours[n].b);
  }
}

TEST(PlyWriter, EmptyCloudHasHeaderOnly) {
  const PlyPointCloud cloud(std::vector<Vec3d>{});
  const ParsedPly p = parsePly(cloud.encode());
  EXPECT_EQ(p.vertices, 0u);
  EXPECT_EQ(p.properties.size(), 3u);
  EXPECT_TRUE(p.body.empty());
  EXPECT_EQ(cloud.header(),
            "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n"
            "property float y\nproperty float z\nend_header\n");
}

TEST(PlyWriter, RejectsBadInput) {
  const std::vector<Vec3d> x = {{0, 0, 0}, {1, 1, 1}};
  PlyPointCloud cloud(x);
  EXPECT_THROW(cloud.addFloat("n_p", std::vector<double>{1.0}), InvalidArgument);     // wrong count
  EXPECT_THROW(cloud.addFloat("x", std::vector<double>{1.0, 2.0}), InvalidArgument);  // taken
  EXPECT_THROW(cloud.addFloat("bad name", std::vector<double>{1.0, 2.0}), InvalidArgument);
  EXPECT_THROW(cloud.addFloat("", std::vector<double>{1.0, 2.0}), InvalidArgument);
  EXPECT_THROW(cloud.addVec3("a", "b", "a", x), InvalidArgument);
  EXPECT_THROW(cloud.addComment("two\nlines"), InvalidArgument);
  cloud.addInt("id", std::vector<std::int32_t>{1, 2});
  EXPECT_THROW(cloud.addInt("id", std::vector<std::int32_t>{1, 2}), InvalidArgument);
  // A non-finite position names the point.
  try {
    PlyPointCloud bad(std::vector<Vec3d>{{0, 0, 0}, {0, std::nan(""), 0}});
    FAIL() << "no exception";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("point 1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(PlyPointCloud(std::vector<Vec3d>{{1e39, 0, 0}}), InvalidArgument);  // overflows float
}

TEST(PlyWriter, WritesFileAtomically) {
  const auto dir = freshDir("lodestone_test_ply_writer");
  const auto path = dir / "frame_0001.ply";
  std::vector<Vec3d> x(1000);
  for (std::size_t n = 0; n < x.size(); ++n) x[n] = {0.001 * double(n), 0.0, -0.002 * double(n)};
  PlyPointCloud cloud(x);
  cloud.write(path.string());
  EXPECT_EQ(readFile(path), cloud.encode());

  // Replacing an existing file; nothing else is left in the directory.
  PlyPointCloud small(std::vector<Vec3d>{{1, 2, 3}});
  small.write(path.string());
  EXPECT_EQ(readFile(path), small.encode());
  std::size_t entries = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    ++entries;
    EXPECT_EQ(e.path().filename(), "frame_0001.ply");
  }
  EXPECT_EQ(entries, 1u);

  // A missing directory: the error names the path.
  const std::string missing = (dir / "no_such_dir" / "f.ply").string();
  try {
    small.write(missing);
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}
