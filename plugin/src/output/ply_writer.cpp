#include "lodestone/plugin/output/ply_writer.h"

#include <cmath>
#include <cstring>

#include "lodestone/plugin/output/atomic_file.h"
#include "lodestone/core/base/error.h"

namespace lodestone::output {
namespace {

void putLe32(std::uint8_t* out, std::uint32_t v) {
  out[0] = std::uint8_t(v);
  out[1] = std::uint8_t(v >> 8);
  out[2] = std::uint8_t(v >> 16);
  out[3] = std::uint8_t(v >> 24);
}

void putFloat(std::uint8_t* out, float f) {
  std::uint32_t bits;
  std::memcpy(&bits, &f, 4);
  putLe32(out, bits);
}

bool validName(const std::string& name) {
  if (name.empty()) return false;
  for (char c : name)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_')) return false;
  return true;
}

}  // namespace

const char* plyTypeName(PlyType type) {
  switch (type) {
    case PlyType::Float32:
      return "float";
    case PlyType::Int32:
      return "int";
    case PlyType::UInt8:
      return "uchar";
  }
  return "?";
}

std::size_t plyTypeSize(PlyType type) { return type == PlyType::UInt8 ? 1 : 4; }

PlyPointCloud::PlyPointCloud(const std::vector<Vec3d>& positions) : PlyPointCloud(positions.data(), positions.size()) {}

PlyPointCloud::PlyPointCloud(const Vec3d* positions, std::size_t count) : count_(count) {
  require(positions != nullptr || count == 0, "PLY point cloud: no positions (null pointer) for ", count, " points");
  // Add all three columns first: a pointer taken between push_backs would
  // dangle once the vector of columns reallocates.
  addColumn("x", PlyType::Float32);
  addColumn("y", PlyType::Float32);
  addColumn("z", PlyType::Float32);
  std::uint8_t* axes[3] = {columns_[0].bytes.data(), columns_[1].bytes.data(), columns_[2].bytes.data()};
  for (std::size_t n = 0; n < count; ++n)
    for (int a = 0; a < 3; ++a) {
      const float f = float(positions[n][a]);
      require(std::isfinite(f), "PLY point cloud: position of point ", n, " is not finite in float: (", positions[n].x,
              ", ", positions[n].y, ", ", positions[n].z, ") m");
      putFloat(axes[a] + 4 * n, f);
    }
}

void PlyPointCloud::checkNew(const std::string& name, std::size_t count) const {
  require(validName(name), "PLY point cloud: property name '", name, "' must be non-empty letters, digits and '_'");
  for (const Column& c : columns_) require(c.name != name, "PLY point cloud: property '", name, "' added twice");
  require(count == count_, "PLY point cloud: property '", name, "' has ", count, " values for ", count_, " points");
}

PlyPointCloud::Column& PlyPointCloud::addColumn(const std::string& name, PlyType type) {
  columns_.push_back(Column{name, type, std::vector<std::uint8_t>(count_ * plyTypeSize(type))});
  return columns_.back();
}

void PlyPointCloud::addFloat(const std::string& name, const double* values, std::size_t count) {
  checkNew(name, count);
  require(values != nullptr || count == 0, "PLY point cloud: property '", name, "': no values (null pointer)");
  Column& c = addColumn(name, PlyType::Float32);
  for (std::size_t n = 0; n < count; ++n) putFloat(c.bytes.data() + 4 * n, float(values[n]));
}

void PlyPointCloud::addFloat(const std::string& name, const std::vector<double>& values) {
  addFloat(name, values.data(), values.size());
}

void PlyPointCloud::addFloat(const std::string& name, const std::vector<float>& values) {
  checkNew(name, values.size());
  Column& c = addColumn(name, PlyType::Float32);
  for (std::size_t n = 0; n < values.size(); ++n) putFloat(c.bytes.data() + 4 * n, values[n]);
}

void PlyPointCloud::addInt(const std::string& name, const std::int32_t* values, std::size_t count) {
  checkNew(name, count);
  require(values != nullptr || count == 0, "PLY point cloud: property '", name, "': no values (null pointer)");
  Column& c = addColumn(name, PlyType::Int32);
  for (std::size_t n = 0; n < count; ++n) putLe32(c.bytes.data() + 4 * n, std::uint32_t(values[n]));
}

void PlyPointCloud::addInt(const std::string& name, const std::vector<std::int32_t>& values) {
  addInt(name, values.data(), values.size());
}

void PlyPointCloud::addUChar(const std::string& name, const std::vector<std::uint8_t>& values) {
  checkNew(name, values.size());
  addColumn(name, PlyType::UInt8).bytes = values;
}

void PlyPointCloud::addVec3(const std::string& nameX, const std::string& nameY, const std::string& nameZ,
                            const std::vector<Vec3d>& values) {
  const std::string names[3] = {nameX, nameY, nameZ};
  for (int a = 0; a < 3; ++a) {
    checkNew(names[a], values.size());
    for (int b = 0; b < a; ++b) require(names[a] != names[b], "PLY point cloud: property '", names[a], "' added twice");
  }
  for (int a = 0; a < 3; ++a) {
    Column& c = addColumn(names[a], PlyType::Float32);
    for (std::size_t n = 0; n < values.size(); ++n) putFloat(c.bytes.data() + 4 * n, float(values[n][a]));
  }
}

void PlyPointCloud::addColours(const std::vector<Rgb>& colours) {
  const char* names[3] = {"red", "green", "blue"};
  for (const char* name : names) checkNew(name, colours.size());
  for (int a = 0; a < 3; ++a) {
    Column& c = addColumn(names[a], PlyType::UInt8);
    for (std::size_t n = 0; n < colours.size(); ++n)
      c.bytes[n] = a == 0 ? colours[n].r : (a == 1 ? colours[n].g : colours[n].b);
  }
}

void PlyPointCloud::addEdges(const std::vector<std::array<std::uint32_t, 2>>& edges) {
  for (const auto& e : edges)
    require(e[0] < count_ && e[1] < count_, "PLY point cloud: edge (", e[0], ", ", e[1], ") names a point beyond the ",
            count_, " points");
  edges_.insert(edges_.end(), edges.begin(), edges.end());
}

void PlyPointCloud::addComment(const std::string& text) {
  require(text.find_first_of("\r\n") == std::string::npos, "PLY point cloud: comment '", text,
          "' must be a single line");
  comments_.push_back(text);
}

std::vector<std::pair<std::string, PlyType>> PlyPointCloud::properties() const {
  std::vector<std::pair<std::string, PlyType>> r;
  for (const Column& c : columns_) r.emplace_back(c.name, c.type);
  return r;
}

std::string PlyPointCloud::header() const {
  std::string h = "ply\nformat binary_little_endian 1.0\n";
  for (const std::string& c : comments_) h += "comment " + c + "\n";
  h += concat("element vertex ", count_, "\n");
  for (const Column& c : columns_) h += concat("property ", plyTypeName(c.type), " ", c.name, "\n");
  if (hasFaces_) h += concat("element face ", faces_.size(), "\nproperty list uchar int vertex_indices\n");
  if (!edges_.empty()) h += concat("element edge ", edges_.size(), "\nproperty int vertex1\nproperty int vertex2\n");
  h += "end_header\n";
  return h;
}

std::vector<std::uint8_t> PlyPointCloud::encode() const {
  const std::string h = header();
  std::size_t record = 0;
  for (const Column& c : columns_) record += plyTypeSize(c.type);
  std::vector<std::uint8_t> out(h.size() + record * count_ + 13 * faces_.size() + 8 * edges_.size());
  std::memcpy(out.data(), h.data(), h.size());
  // Interleave the columns into records, one column at a time (sequential reads).
  std::size_t offset = 0;
  for (const Column& c : columns_) {
    const std::size_t s = plyTypeSize(c.type);
    std::uint8_t* dst = out.data() + h.size() + offset;
    const std::uint8_t* src = c.bytes.data();
    if (s == 4) {
      for (std::size_t n = 0; n < count_; ++n, dst += record, src += 4) std::memcpy(dst, src, 4);
    } else {
      for (std::size_t n = 0; n < count_; ++n, dst += record, ++src) *dst = *src;
    }
    offset += s;
  }
  // Faces: a count byte (3), then three little-endian int32 indices; then
  // edges: two little-endian int32 indices each.
  std::uint8_t* dst = out.data() + h.size() + record * count_;
  for (const auto& t : faces_) {
    *dst++ = 3;
    for (const std::uint32_t v : t) {
      putLe32(dst, v);
      dst += 4;
    }
  }
  for (const auto& edge : edges_) {
    putLe32(dst, edge[0]);
    putLe32(dst + 4, edge[1]);
    dst += 8;
  }
  return out;
}

void PlyPointCloud::setTriangles(const std::vector<std::array<std::uint32_t, 3>>& triangles) {
  for (const auto& t : triangles)
    for (const std::uint32_t v : t)
      if (v >= count_ || v > std::uint32_t(INT32_MAX))
        throw InvalidArgument(concat("PLY triangle vertex index ", v, " out of range (", count_, " vertices)"));
  faces_ = triangles;
  hasFaces_ = true;
}

void PlyPointCloud::write(const std::string& path) const { writeFileAtomically(path, encode()); }

}  // namespace lodestone::output
