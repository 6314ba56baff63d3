// Field-line files: PLY with vertex (x y z B line) and edge elements, OBJ
// with one `l` polyline per line; closed lines joined back to their start.
#include <gtest/gtest.h>

#include <cstring>
#include <sstream>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/output/field_line_files.h"

using namespace lodestone;
using namespace lodestone::output;

namespace {
std::vector<FieldLine> twoLines() {
  FieldLine open, closed;
  open.points = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  open.magnitude = {0.1, 0.2, 0.3};
  closed.points = {{0, 1, 0}, {1, 1, 0}, {1, 2, 0}, {0, 1, 0}};
  closed.magnitude = {0.5, 0.6, 0.7, 0.5};
  closed.closed = true;
  return {open, closed};
}
}  // namespace

TEST(FieldLineFiles, PlyHasVerticesWithBAndEdges) {
  const PlyPointCloud ply = fieldLinesPly(twoLines());
  EXPECT_EQ(ply.size(), 6u);  // the closed line's repeated vertex is not written
  EXPECT_EQ(ply.edgeCount(), 2u + 3u);
  const std::string h = ply.header();
  EXPECT_NE(h.find("element vertex 6\nproperty float x\nproperty float y\nproperty float z\nproperty float B\n"
                   "property int line\nelement edge 5\nproperty int vertex1\nproperty int vertex2\nend_header\n"),
            std::string::npos)
      << h;
  const std::vector<std::uint8_t> bytes = ply.encode();
  ASSERT_EQ(bytes.size(), h.size() + 6 * 20 + 5 * 8);
  // The last edge joins the closed line's last vertex (5) to its first (3).
  std::int32_t last[2];
  std::memcpy(last, bytes.data() + bytes.size() - 8, 8);
  EXPECT_EQ(last[0], 5);
  EXPECT_EQ(last[1], 3);
  // Vertex 4: (1, 1, 0), B = 0.6, line 1.
  float v[4];
  std::memcpy(v, bytes.data() + h.size() + 4 * 20, 16);
  EXPECT_EQ(v[0], 1.0f);
  EXPECT_EQ(v[1], 1.0f);
  EXPECT_FLOAT_EQ(v[3], 0.6f);
  std::int32_t line = 0;
  std::memcpy(&line, bytes.data() + h.size() + 4 * 20 + 16, 4);
  EXPECT_EQ(line, 1);
  PlyPointCloud bad(std::vector<Vec3d>{{0, 0, 0}});
  EXPECT_THROW(bad.addEdges({{0, 1}}), InvalidArgument);
}

TEST(FieldLineFiles, ObjHasOnePolylinePerLine) {
  const std::string obj = fieldLinesObj(twoLines(), "frame 3");
  std::istringstream in(obj);
  std::string line;
  int vertices = 0;
  std::vector<std::string> polylines;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) ++vertices;
    if (line.rfind("l ", 0) == 0) polylines.push_back(line);
  }
  EXPECT_EQ(vertices, 6);
  ASSERT_EQ(polylines.size(), 2u);
  EXPECT_EQ(polylines[0], "l 1 2 3");
  EXPECT_EQ(polylines[1], "l 4 5 6 4");
  EXPECT_NE(obj.find("# frame 3\n"), std::string::npos);
  EXPECT_THROW(writeFieldLines("/tmp/lines.txt", twoLines()), InvalidArgument);
}
