#pragma once
// Wedges: variants of one scene that differ in a few values. Each --vary
// KEY=V1,V2,... names a JSON path into the scene file (docs/farm.md) and its
// values; the wedges are their cartesian product, the first --vary varying
// slowest. This file holds the plan only (paths, values, names, the
// manifest); running them is farm_pool.h (locally) or Slurm (wedge_command).
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace lodestone::examples {

/// One step of a JSON path: an object key, or an array element given by
/// position ([2]) or, for an array of named objects, by name
/// (materials.ferro: the element whose "name" is "ferro").
struct JsonPathStep {
  std::string key;  ///< object key or element name ("" when index >= 0)
  int index = -1;   ///< array position, or -1
};

/// "magnets[0].magnetization" -> {magnets, [0], magnetization}. Throws
/// lodestone::InvalidArgument naming `path` when it is not one.
std::vector<JsonPathStep> parseJsonPath(const std::string& path);

/// Sets the value at `path` in `doc`. The path must lead through existing
/// objects and array elements; its last key may be new to its object (the
/// scene validator then judges it). Throws lodestone::InvalidArgument naming
/// the path and the step that does not exist.
void setJsonPath(nlohmann::json& doc, const std::string& path, const nlohmann::json& value);

/// One --vary: a path and its values, with each value's text as given.
struct WedgeAxis {
  std::string key;
  std::vector<nlohmann::json> values;
  std::vector<std::string> texts;
};

/// "KEY=V1,V2,...": values split at commas outside brackets; each is JSON
/// when it reads as JSON (1e5, true, [0,0,1], "text"), else a string.
/// Throws lodestone::InvalidArgument naming `text` when it has no '=', no
/// key or an empty value.
WedgeAxis parseVary(const std::string& text);

/// One scene of the product.
struct Wedge {
  int index = 0;
  std::string name;  ///< directory name: "w03_magnetization-2e5_mu-0.1"
  std::vector<std::pair<std::string, nlohmann::json>> values;  ///< key, value (in --vary order)
  nlohmann::json scene;
};

/// The cartesian product of `axes` applied to `scene` (the first axis
/// varies slowest). Throws lodestone::InvalidArgument when there is no axis,
/// a key is given twice, a path does not exist in the scene, or the product
/// exceeds `maxWedges`.
std::vector<Wedge> expandWedges(const nlohmann::json& scene, const std::vector<WedgeAxis>& axes,
                                int maxWedges = 10000);

/// The label of a key in wedge names: its last key, or the whole path
/// (non-alphanumerics as '.') when two axes share the last key.
std::vector<std::string> axisLabels(const std::vector<WedgeAxis>& axes);

/// A value's text made safe for a file name ([A-Za-z0-9.+-], others '_').
std::string fileSafe(const std::string& text);

/// Where a wedge's files lie, relative to the wedge directory.
std::string wedgeSceneFile(const Wedge& w);  ///< NAME/scene.json
std::string wedgeOutDir(const Wedge& w);     ///< NAME/out

/// The manifest (wedges.json): the source scene, the axes, and each wedge's
/// index, name, values, scene file and output directory.
nlohmann::json wedgeManifest(const std::string& sourceScene, const std::vector<WedgeAxis>& axes,
                             const std::vector<Wedge>& wedges);
/// The same as CSV: index,name,scene,out, then one column per key.
std::string wedgeManifestCsv(const nlohmann::json& manifest);

}  // namespace lodestone::examples
