// The per-frame outputs and the --outputs list. See outputs.h.
#include "outputs.h"

#include <algorithm>
#include <filesystem>

#include "lodestone/core/base/error.h"

namespace lodestone::examples {

const std::vector<OutputKind>& outputKinds() {
  static const std::vector<OutputKind> kinds{
      {"particles", "frame_NNNN.ply", "particles (x y z, vx vy vz, n_p, material, J)"},
      {"points", "particles_NNNN.vdb", "the particles as OpenVDB points (Houdini)"},
      {"fields", "fields_NNNN.vdb", "the grids of the scene's output.vdb (n, phi, H, M, B, force)"},
      {"surface", "surface_NNNN.vdb", "level sets: surface (all material), surface_<material>"},
      {"mesh", "mesh_NNNN.ply, mesh_NNNN.obj", "the surface as triangles with normals (and velocities in the PLY)"},
      {"volume", "volume_NNNN.vdb", "render volumes: density (volume fraction), vel, magnetization (|M|)"},
      {"field_lines", "field_lines_NNNN.ply, field_lines_NNNN.obj",
       "lines of B from seeds on the magnets and the magnetic material (drawn in the previews)"},
      {"png", "frame_NNNN.png", "a preview render (shaded from the surface mesh when mesh is written)"},
  };
  return kinds;
}

namespace {

const OutputKind* findKind(const std::string& name) {
  for (const OutputKind& k : outputKinds())
    if (name == k.name) return &k;
  return nullptr;
}

std::string knownNames() {
  std::string s;
  for (const OutputKind& k : outputKinds()) s += (s.empty() ? "" : ", ") + std::string(k.name);
  return s;
}

}  // namespace

OutputSelection OutputSelection::sceneDefault(const plugin::SceneOutput& output) {
  OutputSelection s;
  for (const OutputKind& k : outputKinds()) {
    const std::string name = k.name;
    if ((name == "particles" && output.ply) || (name == "points" && output.vdbPoints) ||
        (name == "fields" && !output.vdbFields.empty()) || (name == "png" && output.png))
      s.names_.push_back(name);
  }
  return s;
}

OutputSelection OutputSelection::parse(const std::string& list) {
  std::vector<std::string> given;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t comma = std::min(list.find(',', start), list.size());
    const std::string name = list.substr(start, comma - start);
    if (!findKind(name))
      throw InvalidArgument(concat("--outputs: unknown output '", name, "' (known: ", knownNames(), ")"));
    if (std::find(given.begin(), given.end(), name) != given.end())
      throw InvalidArgument(concat("--outputs: '", name, "' is listed twice"));
    given.push_back(name);
    start = comma + 1;
  }
  OutputSelection s;
  for (const OutputKind& k : outputKinds())
    if (std::find(given.begin(), given.end(), k.name) != given.end()) s.names_.push_back(k.name);
  return s;
}

std::string OutputSelection::check(const std::string& list) {
  try {
    parse(list);
    return "";
  } catch (const InvalidArgument& e) {
    return e.what();
  }
}

bool OutputSelection::has(const std::string& name) const {
  return std::find(names_.begin(), names_.end(), name) != names_.end();
}

void OutputSelection::remove(const std::string& name) {
  names_.erase(std::remove(names_.begin(), names_.end(), name), names_.end());
}

std::string OutputSelection::describe() const {
  std::string s;
  for (const std::string& n : names_) s += concat(s.empty() ? "" : ", ", n, " (", findKind(n)->files, ")");
  return s.empty() ? "nothing" : s;
}

plugin::RenderOutputPaths renderOutputPaths(const OutputSelection& outputs, const std::string& dir,
                                            const std::string& number) {
  const auto path = [&](const std::string& name) { return (std::filesystem::path(dir) / name).string(); };
  plugin::RenderOutputPaths p;
  if (outputs.has("surface")) p.surface = path("surface_" + number + ".vdb");
  if (outputs.has("volume")) p.volume = path("volume_" + number + ".vdb");
  if (outputs.has("mesh")) {
    p.meshPly = path("mesh_" + number + ".ply");
    p.meshObj = path("mesh_" + number + ".obj");
  }
  return p;
}

}  // namespace lodestone::examples
