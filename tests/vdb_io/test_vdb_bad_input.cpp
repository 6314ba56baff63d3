// Absurd VDB inputs to the readers: extreme, non-finite, mirrored or rotated
// transforms, non-finite and negative values, voxels far from the origin.
// Each case has one defined outcome (docs/vdb.md, "Reading"):
//   - a transform that is not a uniform-scale linear map (shear, non-uniform
//     scale, frustum), or one that maps the target grid beyond +-2^30 voxels
//     (where the sampler's integer index coordinates would overflow), throws
//     lodestone::InvalidArgument naming the file and the grid;
//   - any other uniform-scale linear transform (huge or tiny voxels, mirrors,
//     rotations, far voxels) returns the world-space trilinear samples of the
//     file's grid on the target nodes, inactive voxels counting as the
//     background 0: the test computes those samples itself and compares;
//   - the density reader, in addition, refuses negative and non-finite values.
// Transforms that OpenVDB itself refuses to build (voxels of 1e-5 m and less,
// a translation of 1e300 m) cannot occur in a file and are checked to stay
// refused, so that a reader never sees them untested.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <utility>
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

// writeFields' pattern: `value` on the 5 x 5 voxels (at.x + [-2, 2], at.y +
// [-2, 2], at.z), the background 0 elsewhere.
double pattern(long i, long j, long k, double value, const openvdb::Coord& at) {
  return (std::labs(i - at.x()) <= 2 && std::labs(j - at.y()) <= 2 && k == at.z()) ? value : 0.0;
}

// Trilinear sample of the pattern at index-space point u (the 8 voxels
// around floor(u), as openvdb::tools::BoxSampler).
double trilinear(const openvdb::Vec3d& u, double value, const openvdb::Coord& at) {
  const double f[3] = {std::floor(u[0]), std::floor(u[1]), std::floor(u[2])};
  double sum = 0;
  for (int c = 0; c < 8; ++c) {
    double w = 1;
    long idx[3];
    for (int a = 0; a < 3; ++a) {
      const int up = (c >> a) & 1;
      const double t = u[a] - f[a];
      w *= up ? t : 1 - t;
      idx[a] = long(f[a]) + up;
    }
    sum += w * pattern(idx[0], idx[1], idx[2], value, at);
  }
  return sum;
}

// The defined outcome for a uniform-scale linear transform: every node of
// kSpec holds the trilinear sample of the pattern at worldToIndex(node),
// through all three readers (scalar, density, vector: the pattern along z).
void expectSamples(const std::string& path, const std::function<openvdb::Vec3d(const Vec3d&)>& worldToIndex,
                   const std::string& what, double value = double(1e23f),
                   const openvdb::Coord& at = openvdb::Coord(0, 0, 0)) {
  SCOPED_TRACE(what);
  ASSERT_FALSE(path.empty()) << "OpenVDB refused the transform";
  const DenseGrid<double> n = readScalarField(path, "n", kSpec);
  const DenseGrid<double> d = readDensityVdb(path, kSpec);
  const DenseGrid<Vec3d> H = readVec3Field(path, "H", kSpec);
  ASSERT_EQ(n.size(), kSpec.nodeCount());
  // Float values, and the sampler's weights in float-rounded index
  // coordinates: relative 1e-6 of the voxel value.
  const double tol = 1e-6 * value;
  double nonzero = 0;
  for (int k = 0; k < kSpec.dims.k; ++k)
    for (int j = 0; j < kSpec.dims.j; ++j)
      for (int i = 0; i < kSpec.dims.i; ++i) {
        const double e = trilinear(worldToIndex(kSpec.nodePosition(i, j, k)), value, at);
        nonzero += e != 0;
        ASSERT_NEAR(n(i, j, k), e, tol) << "node " << i << " " << j << " " << k;
        ASSERT_EQ(d(i, j, k), n(i, j, k)) << "node " << i << " " << j << " " << k;
        ASSERT_NEAR(H(i, j, k).z, e, tol) << "node " << i << " " << j << " " << k;
        ASSERT_EQ(H(i, j, k).x, 0.0);
        ASSERT_EQ(H(i, j, k).y, 0.0);
      }
  std::printf("%s: %g of %zu nodes inside the pattern's support\n", what.c_str(), nonzero, kSpec.nodeCount());
}

// The defined outcome for a refused transform: all three readers throw
// InvalidArgument naming the file, the grid and `reason`.
void expectRefused(const std::string& path, const std::string& reason, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_FALSE(path.empty()) << "OpenVDB refused the transform";
  const std::vector<std::pair<std::string, std::function<void()>>> readers{
      {"n", [&] { readScalarField(path, "n", kSpec); }},
      {"n", [&] { readDensityVdb(path, kSpec); }},
      {"H", [&] { readVec3Field(path, "H", kSpec); }}};
  for (const auto& [grid, read] : readers) {
    try {
      read();
      ADD_FAILURE() << "grid " << grid << " read without an error";
    } catch (const InvalidArgument& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(path), std::string::npos) << msg;
      EXPECT_NE(msg.find("'" + grid + "'"), std::string::npos) << msg;
      EXPECT_NE(msg.find(reason), std::string::npos) << msg;
    }
  }
}

openvdb::math::Transform::Ptr affine(const openvdb::Mat4R& m) {
  return openvdb::math::Transform::createLinearTransform(m);
}

}  // namespace

TEST(VdbBadInput, ExtremeVoxelSizes) {
  // Voxels of 1e9 m and more: the whole target grid (4 cm) lies within a
  // hair of voxel (0, 0, 0), so every node takes (nearly) its value; 2e-5 m:
  // only the node at the origin falls on the pattern. Both are sampled, not
  // refused.
  int file = 0;
  for (const double h : {2e-5, 1e9, 1e30, 1e300}) {
    const std::string path = writeFields("voxel_" + std::to_string(file++) + ".vdb",
                                         [&] { return openvdb::math::Transform::createLinearTransform(h); });
    expectSamples(path, [&](const Vec3d& x) { return openvdb::Vec3d(x.x / h, x.y / h, x.z / h); },
                  concat("voxel size ", h, " m"));
  }
  // OpenVDB 10 refuses voxels of 1e-5 m and less ("Non-zero scale values
  // required"), so no file can carry them.
  for (const double h : {1e-300, 1e-30, 1e-8})
    EXPECT_TRUE(writeFields("tiny.vdb", [&] { return openvdb::math::Transform::createLinearTransform(h); }).empty())
        << h;
}

TEST(VdbBadInput, MirroredRotatedAndShearedTransforms) {
  const double s = 0.005;
  // A mirror and a rotation are uniform-scale linear maps: sampled in world
  // space. The pattern is offset by one voxel in i so that a reader that
  // ignored the mirror would put it on the wrong side.
  const openvdb::Coord off(1, 0, 0);
  expectSamples(writeFields("mirror.vdb",
                            [&] {
                              return affine(openvdb::Mat4R(-s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 0.0,
                                                           0.0, 0.0, 1.0));
                            },
                            1e23f, off),
                [&](const Vec3d& x) { return openvdb::Vec3d(-x.x / s, x.y / s, x.z / s); }, "mirrored x",
                double(1e23f), off);
  // OpenVDB's matrices act on row vectors: world = (i, j, k, 1) * M.
  const double c = std::cos(0.3), si = std::sin(0.3);
  expectSamples(writeFields("rotated.vdb",
                            [&] {
                              return affine(openvdb::Mat4R(c * s, si * s, 0.0, 0.0, -si * s, c * s, 0.0, 0.0, 0.0, 0.0,
                                                           s, 0.0, 0.0, 0.0, 0.0, 1.0));
                            },
                            1e23f, off),
                [&](const Vec3d& x) {
                  return openvdb::Vec3d((c * x.x + si * x.y) / s, (-si * x.x + c * x.y) / s, x.z / s);
                },
                "rotated by 0.3 rad about z", double(1e23f), off);
  // A shear is not a uniform-scale map: refused.
  expectRefused(writeFields("sheared.vdb",
                            [&] {
                              return affine(openvdb::Mat4R(s, 0.0, 0.0, 0.0, s, s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 0.0,
                                                           0.0, 0.0, 1.0));
                            }),
                "uniform-scale linear map", "sheared");
  // A translation of 1e10 m puts the target grid 2e12 voxels from the file's
  // origin, beyond the sampler's int coordinates: refused, not overflowed.
  expectRefused(writeFields("far_translation.vdb",
                            [&] {
                              return affine(openvdb::Mat4R(s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 1e10,
                                                           -1e10, 1e10, 1.0));
                            }),
                "beyond +-2^30 voxels", "translated by 1e10 m");
  // OpenVDB refuses to build a translation of 1e300 m.
  EXPECT_TRUE(writeFields("huge_translation.vdb", [&] {
                return affine(openvdb::Mat4R(s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 1e300, -1e300,
                                             1e300, 1.0));
              }).empty());
}

TEST(VdbBadInput, VoxelsFarFromTheOriginAreNotAllocatedAsABox) {
  // Voxels 2^30 index units from the origin: a reader that densified the file's
  // bounding box would need exabytes; onto kSpec it is a handful of values,
  // all the background (the voxels are 5e6 m away).
  const openvdb::Coord far(1 << 30, -(1 << 30), 1 << 29);
  const std::string path = writeFields(
      "far_voxels.vdb", [] { return openvdb::math::Transform::createLinearTransform(0.005); }, 1e23f, far);
  expectSamples(path, [](const Vec3d& x) { return openvdb::Vec3d(x.x / 0.005, x.y / 0.005, x.z / 0.005); },
                "voxels at 2^30", double(1e23f), far);
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
