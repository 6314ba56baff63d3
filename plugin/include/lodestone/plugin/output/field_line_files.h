#pragma once
// Field lines (core/stage/field_lines.h) as files a DCC opens as curves:
//   PLY: binary little-endian, one `vertex` element (float x, y, z in m,
//        float B = |B| in T, int line = the line's index) and one `edge`
//        element (int vertex1, vertex2) joining consecutive vertices of
//        each line; a closed line's last vertex is not repeated, an edge
//        joins it back to the first.
//   OBJ: `v x y z` lines then one `l i j k ...` polyline per line (1-based;
//        a closed line repeats its first index at the end). |B| is not part
//        of OBJ: the PLY file carries it.
// Written atomically (atomic_file.h).
#include <string>
#include <vector>

#include "lodestone/core/stage/field_lines.h"
#include "lodestone/plugin/output/ply_writer.h"

namespace lodestone::output {

/// The PLY point cloud with edges described above.
PlyPointCloud fieldLinesPly(const std::vector<FieldLine>& lines);
/// The OBJ text described above; `comment` (one line, may be empty) heads it.
std::string fieldLinesObj(const std::vector<FieldLine>& lines, const std::string& comment = "");
/// Writes `path` as PLY or OBJ by its extension (.ply / .obj, else InvalidArgument).
void writeFieldLines(const std::string& path, const std::vector<FieldLine>& lines, const std::string& comment = "");

}  // namespace lodestone::output
