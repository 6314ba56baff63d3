#pragma once
// The per-frame outputs of `lodestone run` and `lodestone surface`: their
// names (the --outputs list), the files each writes, and the parsing of the
// list, in one place.
#include <string>
#include <vector>

#include "lodestone/plugin/node_builders.h"
#include "lodestone/plugin/scene.h"

namespace lodestone::examples {

struct OutputKind {
  const char* name;   ///< as --outputs names it
  const char* files;  ///< the files it writes in DIR
  const char* what;
};
/// Every output, in the order they are written and printed.
const std::vector<OutputKind>& outputKinds();

/// The outputs a run writes.
class OutputSelection {
 public:
  /// The scene's own choice: particles and png when the scene's output asks,
  /// fields when output.vdb lists grids, points when output.vdb_points.
  static OutputSelection sceneDefault(const plugin::SceneOutput& output);
  /// A comma-separated list of output names ("particles,surface,mesh").
  /// Throws InvalidArgument naming an unknown or repeated name.
  static OutputSelection parse(const std::string& list);
  /// "" when `list` parses, else the reason (for the option's check).
  static std::string check(const std::string& list);

  bool has(const std::string& name) const;
  void remove(const std::string& name);
  /// Surface, mesh or volume.
  bool rendersSurface() const { return has("surface") || has("mesh") || has("volume"); }
  const std::vector<std::string>& names() const { return names_; }
  /// "particles (frame_NNNN.ply), png (frame_NNNN.png), ..." or "nothing".
  std::string describe() const;

 private:
  std::vector<std::string> names_;  // in outputKinds() order
};

/// The paths of the render outputs of frame `number` ("0012") in `dir`.
plugin::RenderOutputPaths renderOutputPaths(const OutputSelection& outputs, const std::string& dir,
                                            const std::string& number);

}  // namespace lodestone::examples
