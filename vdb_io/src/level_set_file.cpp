// Level sets from VDB files and OBJ meshes as SampledSdf. See level_set_file.h.
#include "lodestone/vdb_io/level_set_file.h"

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>

#include "lodestone/core/base/error.h"
#include "lodestone/vdb_io/grid_conversion.h"
#include "vdb_atomic_write.h"

namespace lodestone {

namespace {

std::string levelSetName(const std::string& path, const std::string& grid) {
  return concat("VDB file '", path, "', grid '", grid, "'");
}

/// Parses a whole token as a finite double; false otherwise.
bool parseDouble(const std::string& token, double& out) {
  if (token.empty()) return false;
  char* end = nullptr;
  errno = 0;
  out = std::strtod(token.c_str(), &end);
  return *end == '\0' && errno == 0 && std::isfinite(out);
}

/// Parses a whole token as a (possibly negative) integer; false otherwise.
bool parseIndex(const std::string& token, long long& out) {
  if (token.empty()) return false;
  char* end = nullptr;
  errno = 0;
  out = std::strtoll(token.c_str(), &end, 10);
  return *end == '\0' && errno == 0;
}

openvdb::FloatGrid::Ptr meshToLevelSetGrid(const TriangleMesh& mesh, const MeshLevelSetOptions& options,
                                           const std::string& who) {
  initializeVdb();
  require(std::isfinite(options.voxelSize) && options.voxelSize > 0, who,
          ": voxel size must be a positive finite length in m, got ", options.voxelSize);
  require(options.halfWidth >= 1 && options.halfWidth <= 64, who, ": narrow-band half width must be 1..64 voxels, got ",
          options.halfWidth);
  require(!mesh.triangles.empty(), who, ": the mesh has no triangles");
  Vec3d lo = mesh.vertices.front(), hi = lo;
  std::vector<openvdb::Vec3s> points;
  points.reserve(mesh.vertices.size());
  for (const Vec3d& v : mesh.vertices) {
    require(isFinite(v), who, ": vertex (", v.x, ", ", v.y, ", ", v.z, ") is not finite");
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], v[a]);
      hi[a] = std::max(hi[a], v[a]);
    }
    points.emplace_back(float(v.x), float(v.y), float(v.z));
  }
  const Vec3d extent = hi - lo;
  const double cells =
      (extent.x / options.voxelSize + 1) * (extent.y / options.voxelSize + 1) * (extent.z / options.voxelSize + 1);
  require(cells <= 1e9, who, ": voxel size ", options.voxelSize, " m gives about ", cells,
          " voxels over the mesh's bounding box; use a larger voxel size");
  std::vector<openvdb::Vec3I> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    for (const std::uint32_t v : t)
      require(v < mesh.vertices.size(), who, ": triangle vertex index ", v, " out of range (", mesh.vertices.size(),
              " vertices)");
    triangles.emplace_back(t[0], t[1], t[2]);
  }
  const auto xf = openvdb::math::Transform::createLinearTransform(options.voxelSize);
  auto grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xf, points, triangles, float(options.halfWidth));
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  return grid;
}

}  // namespace

SampledSdf readLevelSetVdb(const std::string& path, const std::string& gridName) {
  const auto grid = readVdbFloatGrid(path, gridName);
  return toSampledSdf(*grid, levelSetName(path, gridName));
}

TriangleMesh parseObj(const std::string& text, const std::string& sourceName) {
  TriangleMesh mesh;
  std::istringstream in(text);
  std::string line;
  int lineNo = 0;
  struct PendingFace {
    std::vector<long long> corners;
    int line;
  };
  std::vector<PendingFace> faces;
  while (std::getline(in, line)) {
    ++lineNo;
    const auto where = [&]() { return concat(sourceName, ":", lineNo, ": "); };
    std::istringstream ls(line);
    std::string keyword;
    if (!(ls >> keyword) || keyword[0] == '#') continue;
    std::vector<std::string> tokens;
    for (std::string t; ls >> t;) {
      if (t[0] == '#') break;
      tokens.push_back(t);
    }
    if (keyword == "v") {
      require(tokens.size() == 3 || tokens.size() == 4 || tokens.size() == 6, where(),
              "a vertex needs 3 coordinates (x y z [w], or x y z r g b), got ", tokens.size(), " values");
      Vec3d p;
      for (int a = 0; a < 3; ++a)
        require(parseDouble(tokens[std::size_t(a)], p[a]), where(), "vertex coordinate '", tokens[std::size_t(a)],
                "' is not a finite number");
      mesh.vertices.push_back(p);
    } else if (keyword == "f") {
      require(tokens.size() >= 3, where(), "a face needs at least 3 vertices, got ", tokens.size());
      PendingFace f{{}, lineNo};
      for (const std::string& t : tokens) {
        long long idx = 0;
        const std::string first = t.substr(0, t.find('/'));
        require(parseIndex(first, idx) && idx != 0, where(), "face vertex '", t, "' is not a vertex index (1-based)");
        // Negative indices count back from the vertices read so far.
        if (idx < 0) {
          idx += (long long)mesh.vertices.size() + 1;
          require(idx >= 1, where(), "relative vertex index ", first, " reaches before the first vertex");
        }
        f.corners.push_back(idx - 1);
      }
      faces.push_back(std::move(f));
    }
    // Other statements (vn, vt, o, g, s, usemtl, mtllib, l, p, ...) carry no shape: ignored.
  }
  require(!faces.empty(), sourceName, ": no faces (f lines); a closed triangle mesh is needed");
  for (const PendingFace& f : faces) {
    for (const long long c : f.corners)
      require(c < (long long)mesh.vertices.size(), sourceName, ":", f.line, ": vertex index ", c + 1,
              " out of range (the file has ", mesh.vertices.size(), " vertices)");
    for (std::size_t k = 1; k + 1 < f.corners.size(); ++k)  // fan triangulation
      mesh.triangles.push_back(
          {std::uint32_t(f.corners[0]), std::uint32_t(f.corners[k]), std::uint32_t(f.corners[k + 1])});
  }
  return mesh;
}

TriangleMesh readObj(const std::string& path) {
  std::error_code ec;
  require(std::filesystem::is_regular_file(path, ec), "OBJ file '", path, "': not found or not a regular file");
  std::ifstream in(path, std::ios::binary);
  require(bool(in), "OBJ file '", path, "': cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  require(!in.bad(), "OBJ file '", path, "': read error");
  return parseObj(text.str(), concat("OBJ file '", path, "'"));
}

SampledSdf meshToSampledSdf(const TriangleMesh& mesh, const MeshLevelSetOptions& options, const std::string& who) {
  const auto grid = meshToLevelSetGrid(mesh, options, who);
  return toSampledSdf(*grid, who);
}

SampledSdf levelSetFromObj(const std::string& path, double voxelSize) {
  MeshLevelSetOptions o;
  o.voxelSize = voxelSize;
  return meshToSampledSdf(readObj(path), o, concat("OBJ file '", path, "'"));
}

void writeMeshLevelSetVdb(const std::string& path, const TriangleMesh& mesh, const MeshLevelSetOptions& options,
                          const std::string& gridName) {
  auto grid = meshToLevelSetGrid(mesh, options, concat("level set for '", path, "'"));
  grid->setName(gridName);
  grid->insertMeta("units", openvdb::StringMetadata("m"));
  grid->insertMeta("description", openvdb::StringMetadata("signed distance, negative inside"));
  openvdb::MetaMap meta;
  meta.insertMeta("creator", openvdb::StringMetadata("Lodestone " LODESTONE_VERSION_STRING));
  meta.insertMeta("lodestone_version", openvdb::StringMetadata(LODESTONE_VERSION_STRING));
  detail::writeVdbAtomically(path, {grid}, meta);
}

}  // namespace lodestone
