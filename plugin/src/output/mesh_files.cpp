// Triangle meshes as PLY and OBJ files. See mesh_files.h.
#include "lodestone/plugin/output/mesh_files.h"

#include <cstdio>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/output/atomic_file.h"

namespace lodestone::output {

namespace {

void checkArrays(const TriangleMesh& mesh) {
  require(mesh.normals.empty() || mesh.normals.size() == mesh.vertices.size(), "mesh: ", mesh.normals.size(),
          " normals for ", mesh.vertices.size(), " vertices");
  require(mesh.velocities.empty() || mesh.velocities.size() == mesh.vertices.size(), "mesh: ",
          mesh.velocities.size(), " velocities for ", mesh.vertices.size(), " vertices");
}

}  // namespace

PlyPointCloud meshPly(const TriangleMesh& mesh) {
  checkArrays(mesh);
  PlyPointCloud ply(mesh.vertices);
  if (!mesh.normals.empty()) ply.addVec3("nx", "ny", "nz", mesh.normals);
  if (!mesh.velocities.empty()) ply.addVec3("vx", "vy", "vz", mesh.velocities);
  ply.setTriangles(mesh.triangles);
  return ply;
}

void writeMeshPly(const std::string& path, const TriangleMesh& mesh, const std::string& comment) {
  PlyPointCloud ply = meshPly(mesh);
  if (!comment.empty()) ply.addComment(comment);
  ply.write(path);
}

std::string meshObj(const TriangleMesh& mesh, const std::string& comment) {
  checkArrays(mesh);
  require(comment.find_first_of("\r\n") == std::string::npos, "OBJ comment must be one line");
  std::string out;
  out.reserve(mesh.vertices.size() * 80 + mesh.triangles.size() * 40);
  if (!comment.empty()) out += "# " + comment + "\n";
  char line[160];
  for (const Vec3d& v : mesh.vertices) {
    require(isFinite(v), "mesh: vertex (", v.x, ", ", v.y, ", ", v.z, ") is not finite");
    std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", v.x, v.y, v.z);
    out += line;
  }
  for (const Vec3d& n : mesh.normals) {
    std::snprintf(line, sizeof line, "vn %.6g %.6g %.6g\n", n.x, n.y, n.z);
    out += line;
  }
  const bool normals = !mesh.normals.empty();
  for (const auto& t : mesh.triangles) {
    for (const std::uint32_t v : t)
      require(v < mesh.vertices.size(), "mesh: triangle vertex index ", v, " out of range (", mesh.vertices.size(),
              " vertices)");
    const unsigned a = t[0] + 1, b = t[1] + 1, c = t[2] + 1;
    if (normals)
      std::snprintf(line, sizeof line, "f %u//%u %u//%u %u//%u\n", a, a, b, b, c, c);
    else
      std::snprintf(line, sizeof line, "f %u %u %u\n", a, b, c);
    out += line;
  }
  return out;
}

void writeMeshObj(const std::string& path, const TriangleMesh& mesh, const std::string& comment) {
  const std::string text = meshObj(mesh, comment);
  writeFileAtomically(path, text);
}

}  // namespace lodestone::output
