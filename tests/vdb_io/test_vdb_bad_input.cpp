// Absurd VDB inputs to the readers: extreme, non-finite, mirrored or rotated
// transforms, non-finite and negative values, voxels far from the origin.
// Each reader must either throw lodestone::Error naming the file, or return
// finite values of the expected size; never crash, hang, allocate the file's
// bounding box or return NaN.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/grid.h"
#include "lodestone/vdb_io/field_file.h"
#include "lodestone/vdb_io/grid_conversion.h"

using namespace lodestone;
namespace fs = std::filesystem;

namespace {

const GridSpec kSpec{{-0.02, -0.02, -0.02}, 0.005, {9, 9, 9}};

fs::path scratch() {
  const fs::path dir = fs::temp_directory_path() / ("lodestone_vdb_bad_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

// Writes a FloatGrid "n" and a Vec3fGrid "H" with a few voxels around the
// origin (index space) under `transform`.
// Returns "" when OpenVDB refuses the transform itself.
std::string writeFields(const std::string& name, const std::function<openvdb::math::Transform::Ptr()>& makeTransform,
                        float value = 1e23f, openvdb::Coord at = openvdb::Coord(0, 0, 0)) {
  openvdb::math::Transform::Ptr transform;
  try {
    transform = makeTransform();
  } catch (const openvdb::Exception&) {
    return "";
  }
  initializeVdb();
  auto n = openvdb::FloatGrid::create(0.0f);
  n->setName("n");
  auto H = openvdb::Vec3fGrid::create(openvdb::Vec3f(0));
  H->setName("H");
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j) {
      n->tree().setValue(at.offsetBy(i, j, 0), value);
      H->tree().setValue(at.offsetBy(i, j, 0), openvdb::Vec3f(0, 0, value));
    }
  n->setTransform(transform);
  H->setTransform(transform->copy());
  const std::string path = (scratch() / name).string();
  openvdb::io::File(path).write({n, H});
  return path;
}

// The reader either throws Error naming the file or returns finite values.
template <typename T>
void expectFiniteOrNamedError(const std::function<DenseGrid<T>()>& read, const std::string& path,
                              const std::string& what) {
  SCOPED_TRACE(what);
  try {
    const DenseGrid<T> g = read();
    ASSERT_EQ(g.size(), kSpec.nodeCount());
    for (std::size_t i = 0; i < g.size(); ++i) {
      if constexpr (std::is_same_v<T, double>) {
        ASSERT_TRUE(std::isfinite(g[i])) << "node " << i;
      } else {
        ASSERT_TRUE(isFinite(g[i])) << "node " << i;
      }
    }
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

void readAll(const std::string& path, const std::string& what) {
  if (path.empty()) return;  // OpenVDB would not even build that transform
  expectFiniteOrNamedError<double>([&] { return readScalarField(path, "n", kSpec); }, path, what + " (scalar)");
  expectFiniteOrNamedError<double>([&] { return readDensityVdb(path, kSpec); }, path, what + " (density)");
  expectFiniteOrNamedError<Vec3d>([&] { return readVec3Field(path, "H", kSpec); }, path, what + " (vector)");
}

openvdb::math::Transform::Ptr affine(const openvdb::Mat4R& m) {
  return openvdb::math::Transform::createLinearTransform(m);
}

}  // namespace

TEST(VdbBadInput, ExtremeVoxelSizes) {
  int file = 0;
  for (const double h : {1e-300, 1e-30, 1e-9, 1e9, 1e30, 1e300}) {
    const std::string path = writeFields("voxel_" + std::to_string(file++) + ".vdb",
                                         [&] { return openvdb::math::Transform::createLinearTransform(h); });
    readAll(path, "voxel size " + std::to_string(h) + " m");
  }
}

TEST(VdbBadInput, MirroredRotatedAndShearedTransforms) {
  const double s = 0.005;
  readAll(writeFields("mirror.vdb",
                      [&] {
                        return affine(
                            openvdb::Mat4R(-s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, 0.0, 1.0));
                      }),
          "mirrored x");
  const double c = std::cos(0.3) * s, si = std::sin(0.3) * s;
  readAll(writeFields("rotated.vdb",
                      [&] {
                        return affine(
                            openvdb::Mat4R(c, si, 0.0, 0.0, -si, c, 0.0, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, 0.0, 1.0));
                      }),
          "rotated");
  readAll(writeFields("sheared.vdb",
                      [&] {
                        return affine(
                            openvdb::Mat4R(s, 0.0, 0.0, 0.0, s, s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, 0.0, 1.0));
                      }),
          "sheared");
  readAll(writeFields("far_translation.vdb",
                      [&] {
                        return affine(openvdb::Mat4R(s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 1e300,
                                                     -1e300, 1e300, 1.0));
                      }),
          "translated by 1e300 m");
}

TEST(VdbBadInput, VoxelsFarFromTheOriginAreNotAllocatedAsABox) {
  // Voxels 2^30 index units from the origin: a reader that densified the file's
  // bounding box would need exabytes; onto kSpec it is a handful of values.
  const std::string path = writeFields(
      "far_voxels.vdb", [] { return openvdb::math::Transform::createLinearTransform(0.005); }, 1e23f,
      openvdb::Coord(1 << 30, -(1 << 30), 1 << 29));
  readAll(path, "voxels at 2^30");
}

TEST(VdbBadInput, NonFiniteAndNegativeDensitiesAreRefusedByTheDensityReader) {
  for (const float v : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -1e20f}) {
    const std::string path = writeFields(
        "bad_values_" + std::to_string(v) + ".vdb",
        [] { return openvdb::math::Transform::createLinearTransform(0.005); }, v);
    try {
      readDensityVdb(path, kSpec);
      ADD_FAILURE() << "density " << v << " accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
}
