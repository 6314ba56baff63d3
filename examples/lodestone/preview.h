#pragma once
// Per-frame preview of a simulation state: particles shaded by material
// (magnetic materials dark, like ferrofluid), magnets drawn as solid shapes
// (red north half is not modelled: one colour), colliders as wireframes, over
// a ground grid at the bottom of the domain.
#include <string>
#include <vector>

#include "lodestone/plugin/output/colormap.h"
#include "lodestone/core/base/triangle_mesh.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/stage/field_lines.h"
#include "lodestone/plugin/scene.h"

namespace lodestone::examples {

/// Renders the solver's current state as the scene's output settings ask,
/// with the field lines (if any) coloured by |B|. The automatic camera
/// frames the domain.
output::RgbImage renderPreview(const plugin::Scene& scene, const MpmSolver& solver,
                               const std::vector<FieldLine>& fieldLines = {});

/// The same with the material drawn as `surface` (a surface mesh of the
/// particles, m) instead of particles; the automatic camera frames the
/// mesh's bounding box.
output::RgbImage renderMeshPreview(const plugin::Scene& scene, const MpmSolver& solver, const TriangleMesh& surface,
                                   const std::vector<FieldLine>& fieldLines = {});

/// The run's contact_sheet.png: thumbnails (160 pixels wide) of at most 48
/// of the previews the run renders, evenly spaced over its frames, 8 a row.
class ContactSheetCollector {
 public:
  /// For the frames first..last of a run.
  ContactSheetCollector(int first, int last);
  /// Keeps a thumbnail of `preview` when `frame` is one the sheet shows.
  void add(int frame, const output::RgbImage& preview);
  bool empty() const { return thumbnails_.empty(); }
  /// Writes the sheet (PNG) when it holds a thumbnail.
  void write(const std::string& path) const;

 private:
  int first_ = 0, stride_ = 1;
  std::vector<output::RgbImage> thumbnails_;
};

}  // namespace lodestone::examples
