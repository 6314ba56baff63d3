// `lodestone surface DIR`. See surface_command.h.
#include "surface_command.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/plugin/output/progress.h"
#include "lodestone/plugin/scene.h"
#include "lodestone/vdb_io/point_file.h"
#include "run_directory.h"

namespace fs = std::filesystem;

namespace lodestone::examples {

namespace {

/// The particles of a cache file as MpmParticles: position, velocity,
/// material, and the volume of the file's radius pscale (mass is not used).
MpmParticles cacheParticles(const ParticleVdbData& data) {
  MpmParticles p;
  for (std::size_t i = 0; i < data.size(); ++i) {
    const double r = data.pscale[i];
    const double volume = 4.0 / 3.0 * kPi * r * r * r;
    if (!(volume > 0)) continue;
    p.add(data.x[i], data.v[i], volume, volume, data.count[i], data.material[i]);
  }
  return p;
}

}  // namespace

int surfaceCommand(const SurfaceCommandArgs& a) {
  const OutputSelection outputs = OutputSelection::parse(a.outputs);
  for (const std::string& n : outputs.names())
    if (n != "surface" && n != "mesh" && n != "volume")
      throw InvalidArgument(concat("--outputs: lodestone surface writes surface, mesh and volume; '", n,
                                   "' comes from lodestone run"));
  std::unique_ptr<tbb::global_control> threads;
  if (a.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    std::size_t(a.threads));
  const fs::path manifest = fs::path(a.dir) / RunDirectory::kManifest;
  if (!fs::is_regular_file(manifest))
    throw Error(concat("'", a.dir, "' is not a run directory of lodestone run (no ", RunDirectory::kManifest, ")"));
  nlohmann::json record;
  try {
    std::ifstream in(manifest);
    record = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    throw Error(concat("cannot read '", manifest.string(), "': ", e.what()));
  }
  const RunIdentity identity = RunIdentity::fromJson(record.at("identity"));
  // The scene's surfacing settings and material names, when its file is still there.
  plugin::SurfaceSettings settings;
  std::vector<std::string> names;
  try {
    const plugin::Scene scene = plugin::loadScene(identity.sceneFile);
    settings = scene.output.surface;
    names = scene.materialNames;
  } catch (const std::exception& e) {
    std::printf("note: the run's scene '%s' could not be read (%s): default surface settings, materials named "
                "material<k>\n",
                identity.sceneFile.c_str(), e.what());
  }
  if (!a.method.empty()) settings.method = a.method;
  if (a.voxelSize >= 0) settings.voxelSize = a.voxelSize;
  // Holds the directory's lock: no run writes into it meanwhile.
  const RunDirectory directory(a.dir, identity, false);

  std::vector<int> frames;
  for (const int f : frameFiles(a.dir, "particles_", "vdb"))
    if (a.last == 0 || (f >= a.first && f <= a.last)) frames.push_back(f);
  if (frames.empty())
    throw Error(concat("no particles_NNNN.vdb", a.last ? concat(" of frames ", a.first, "..", a.last) : "", " in '",
                       a.dir, "': write the particle cache with output.vdb_points or lodestone run --outputs points"));
  std::printf("%s: %zu frames (%d..%d), writing %s; surface method %s, voxel %s\n", a.dir.c_str(), frames.size(),
              frames.front(), frames.back(), outputs.describe().c_str(), settings.method.c_str(),
              settings.voxelSize > 0 ? concat(settings.voxelSize, " m").c_str() : "the particle spacing");
  std::fflush(stdout);

  std::mutex lock;
  output::ProgressOptions progressOptions{output::isTerminal(stdout)};
  output::ProgressPrinter progress(std::cout, int(frames.size()), progressOptions);
  int done = 0;
  plugin::RenderOutputCost total;
  std::vector<std::string> failures;
  const auto t0 = std::chrono::steady_clock::now();
  // Frames are independent: in parallel, each also parallel inside.
  tbb::parallel_for(std::size_t(0), frames.size(), std::size_t(1), [&](std::size_t k) {
    const int frame = frames[k];
    const std::string number = frameNumber(frame);
    try {
      const ParticleVdbData data = readParticlesVdb((fs::path(a.dir) / ("particles_" + number + ".vdb")).string());
      plugin::MagnetizationInput magnetization;
      const fs::path fields = fs::path(a.dir) / ("fields_" + number + ".vdb");
      if (fs::is_regular_file(fields)) magnetization.file = fields.string();
      const plugin::RenderOutputCost c = plugin::writeRenderOutputs(
          renderOutputPaths(outputs, a.dir, number), cacheParticles(data), names, settings, frame, data.time,
          magnetization);
      const std::lock_guard<std::mutex> guard(lock);
      total.surface += c.surface;
      total.mesh += c.mesh;
      total.volume += c.volume;
      total.triangles += c.triangles;
      total.voxelSize = c.voxelSize;
      progress.update(++done, output::formatStageSplit({{"surface", c.surface}, {"mesh", c.mesh}, {"volume", c.volume}}));
    } catch (const std::exception& e) {
      const std::lock_guard<std::mutex> guard(lock);
      failures.push_back(concat("frame ", frame, ": ", e.what()));
      progress.message(failures.back());
    }
  });
  progress.finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double n = double(std::max(done, 1));
  std::printf("wrote %d frames to %s in %.3g s (voxel %.4g m); per frame: surface %.3g s, mesh %.3g s (%.0f "
              "triangles), volume %.3g s\n",
              done, a.dir.c_str(), wall, total.voxelSize, total.surface / n, total.mesh / n,
              double(total.triangles) / n, total.volume / n);
  if (!failures.empty()) {
    std::fprintf(stderr, "lodestone: %zu frames failed:\n", failures.size());
    for (const std::string& f : failures) std::fprintf(stderr, "  %s\n", f.c_str());
    return 1;
  }
  return 0;
}

}  // namespace lodestone::examples
