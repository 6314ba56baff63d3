#pragma once
// Binary little-endian PLY point clouds and triangle meshes: the per-frame
// particle output of the `lodestone` program and its surface meshes (readable by ParaView, CloudCompare, MeshLab, Houdini,
// Blender importers and numpy in a few lines). One `vertex` element with
// float x, y, z (m) and any number of further per-point properties: float
// (velocity vx, vy, vz in m/s, n_p...), int (material id...) or uchar
// (red, green, blue preview colours). Files are written atomically
// (atomic_file.h), so a viewer polling the output folder never reads a
// half-written frame.
//
// Layout written:
//   ply
//   format binary_little_endian 1.0
//   comment <each comment>
//   element vertex <N>
//   property float x
//   property float y
//   property float z
//   property <float|int|uchar> <name>   (in the order added)
//   element face <T>                     (only with setTriangles)
//   property list uchar int vertex_indices
//   element edge <E>                     (only when edges were added)
//   property int vertex1
//   property int vertex2
//   end_header
// followed by N records of the properties in that order, packed,
// little-endian, then T faces (the byte 3 and three int32 vertex indices),
// then E records of two int vertex indices (polylines: field lines).
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "lodestone/plugin/output/colormap.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone::output {

enum class PlyType { Float32, Int32, UInt8 };
/// "float", "int", "uchar" (the PLY type names).
const char* plyTypeName(PlyType type);
/// Bytes per value: 4, 4, 1.
std::size_t plyTypeSize(PlyType type);

class PlyPointCloud {
 public:
  /// Positions in m, stored as float. Throws lodestone::InvalidArgument naming
  /// the first point whose position is not finite (in float).
  explicit PlyPointCloud(const std::vector<Vec3d>& positions);
  PlyPointCloud(const Vec3d* positions, std::size_t count);

  std::size_t size() const { return count_; }

  /// Per-point properties: `values` must hold size() entries (else
  /// InvalidArgument). Names: letters, digits and '_', unique, not x/y/z.
  /// Doubles are rounded to float; non-finite attribute values are written
  /// as they are.
  void addFloat(const std::string& name, const std::vector<double>& values);
  void addFloat(const std::string& name, const std::vector<float>& values);
  void addFloat(const std::string& name, const double* values, std::size_t count);
  void addInt(const std::string& name, const std::vector<std::int32_t>& values);
  void addInt(const std::string& name, const std::int32_t* values, std::size_t count);
  void addUChar(const std::string& name, const std::vector<std::uint8_t>& values);
  /// Three float properties from a vector attribute, e.g. {"vx", "vy", "vz"}.
  void addVec3(const std::string& nameX, const std::string& nameY, const std::string& nameZ,
               const std::vector<Vec3d>& values);
  /// uchar red, green, blue (the names viewers use for point colours).
  void addColours(const std::vector<Rgb>& colours);
  /// Edges between points (0-based indices < size(), else InvalidArgument),
  /// written as the standard `edge` element (vertex1, vertex2).
  void addEdges(const std::vector<std::array<std::uint32_t, 2>>& edges);
  std::size_t edgeCount() const { return edges_.size(); }
  /// Makes the file a triangle mesh: one face per triangle (0-based vertex
  /// indices, each < size(), else InvalidArgument naming it).
  void setTriangles(const std::vector<std::array<std::uint32_t, 3>>& triangles);
  /// A header comment (one line: no '\n' or '\r'), e.g. "units: m, m/s".
  void addComment(const std::string& text);

  /// Names and types of all properties, x, y, z first.
  std::vector<std::pair<std::string, PlyType>> properties() const;
  /// The header text (up to and including "end_header\n").
  std::string header() const;
  /// The whole file: header then packed records.
  std::vector<std::uint8_t> encode() const;
  /// Writes encode() to `path` atomically; lodestone::Error names `path` on failure.
  void write(const std::string& path) const;

 private:
  struct Column {
    std::string name;
    PlyType type;
    std::vector<std::uint8_t> bytes;  // count_ values, little-endian
  };
  void checkNew(const std::string& name, std::size_t count) const;
  Column& addColumn(const std::string& name, PlyType type);

  std::size_t count_ = 0;
  std::vector<std::string> comments_;
  std::vector<Column> columns_;
  std::vector<std::array<std::uint32_t, 2>> edges_;
  std::vector<std::array<std::uint32_t, 3>> faces_;
  bool hasFaces_ = false;
};

}  // namespace lodestone::output
