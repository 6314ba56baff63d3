#include "lodestone/plugin/output/field_line_files.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/output/atomic_file.h"

namespace lodestone::output {

namespace {
/// A closed line's vertices without the repeated last one.
std::size_t ownVertices(const FieldLine& line) {
  return line.closed && line.points.size() > 1 ? line.points.size() - 1 : line.points.size();
}
}  // namespace

PlyPointCloud fieldLinesPly(const std::vector<FieldLine>& lines) {
  std::vector<Vec3d> points;
  std::vector<double> magnitude;
  std::vector<std::int32_t> index;
  std::vector<std::array<std::uint32_t, 2>> edges;
  for (std::size_t l = 0; l < lines.size(); ++l) {
    const FieldLine& line = lines[l];
    const std::size_t n = ownVertices(line), first = points.size();
    for (std::size_t i = 0; i < n; ++i) {
      points.push_back(line.points[i]);
      magnitude.push_back(line.magnitude[i]);
      index.push_back(std::int32_t(l));
      if (i > 0) edges.push_back({std::uint32_t(first + i - 1), std::uint32_t(first + i)});
    }
    if (line.closed && n > 2) edges.push_back({std::uint32_t(first + n - 1), std::uint32_t(first)});
  }
  PlyPointCloud ply(points);
  ply.addFloat("B", magnitude);
  ply.addInt("line", index);
  ply.addEdges(edges);
  ply.addComment("field lines of the magnetic induction B; units m, T");
  return ply;
}

std::string fieldLinesObj(const std::vector<FieldLine>& lines, const std::string& comment) {
  require(comment.find_first_of("\r\n") == std::string::npos, "field-line OBJ: comment must be one line");
  std::string text = "# field lines of the magnetic induction B, m\n";
  if (!comment.empty()) text += "# " + comment + "\n";
  char buf[96];
  for (const FieldLine& line : lines)
    for (std::size_t i = 0; i < ownVertices(line); ++i) {
      std::snprintf(buf, sizeof buf, "v %.9g %.9g %.9g\n", line.points[i].x, line.points[i].y, line.points[i].z);
      text += buf;
    }
  std::size_t first = 1;
  for (const FieldLine& line : lines) {
    const std::size_t n = ownVertices(line);
    if (n >= 2) {
      text += "l";
      for (std::size_t i = 0; i < n; ++i) text += " " + std::to_string(first + i);
      if (line.closed && n > 2) text += " " + std::to_string(first);
      text += "\n";
    }
    first += n;
  }
  return text;
}

void writeFieldLines(const std::string& path, const std::vector<FieldLine>& lines, const std::string& comment) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext == ".ply") {
    PlyPointCloud ply = fieldLinesPly(lines);
    if (!comment.empty()) ply.addComment(comment);
    ply.write(path);
  } else if (ext == ".obj") {
    writeFileAtomically(path, fieldLinesObj(lines, comment));
  } else {
    throw InvalidArgument(concat("field lines: '", path, "' must end in .ply or .obj"));
  }
}

}  // namespace lodestone::output
