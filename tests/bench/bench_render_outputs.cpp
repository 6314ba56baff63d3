// lodestone-bench-render-outputs: cost per frame and file size of each
// per-frame output (particles PLY, surface level sets, mesh PLY/OBJ, render
// volumes) of example scenes, for both surface methods, at the default
// resolution (voxel = the particle spacing). Prints a table and writes CSV
// (docs/vdb.md, docs/accuracy_vs_time.md). Timings are never asserted.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/base/error.h"
#include "lodestone/plugin/node_builders.h"
#include "lodestone/plugin/output/ply_writer.h"
#include "lodestone/plugin/scene.h"

using namespace lodestone;
using namespace lodestone::plugin;
namespace fs = std::filesystem;

int main(int argc, char** argv) {
  try {
    std::vector<std::string> scenes{"ferrofluid_3d.json", "spike.json", "slime_and_magnet.json"};
    int frames = 2;
    std::string csvPath = "bench_render_outputs.csv";
    CLI::App app("lodestone-bench-render-outputs: cost and size of the per-frame render outputs", "");
    cli::helpLayout(app, 24);
    app.add_option("SCENE.json", scenes, "scenes (names in examples/scenes or paths)")->type_name("");
    cli::addNumber(app, "--frames", frames, "frames simulated before measuring (0: the initial state)")
        ->type_name("N")
        ->check(cli::wholeNumber(0, 1000))
        ->default_str(cli::formatNumber(frames));
    app.add_option("--csv", csvPath, "CSV output")->type_name("FILE")->capture_default_str();
    if (const std::optional<int> code = cli::parse(app, argc, argv)) return *code;

    const fs::path dir = fs::temp_directory_path() / "lodestone_bench_render_outputs";
    fs::create_directories(dir);
    std::ofstream csv(csvPath);
    require(bool(csv), "cannot write ", csvPath);
    csv << "scene,particles,method,voxel_m,surface_s,mesh_s,volume_s,particles_ply_s,triangles,surface_bytes,"
           "mesh_ply_bytes,mesh_obj_bytes,volume_bytes,particles_ply_bytes\n";
    std::printf("%-22s %9s %-8s %9s %9s %9s %9s %9s %9s %10s %10s %10s %10s\n", "scene", "particles", "method",
                "voxel mm", "surface s", "mesh s", "volume s", "ply s", "triangles", "surface", "mesh.ply",
                "mesh.obj", "volume");
    for (const std::string& name : scenes) {
      const std::string path = fs::exists(name) ? name : std::string(LODESTONE_SCENES_DIR) + "/" + name;
      Scene scene = loadScene(path);
      auto solver = buildSolver(scene);
      for (int f = 0; f < frames && f < scene.frames; ++f) solver->advanceFrame(scene.frameDuration());
      const MpmParticles& p = solver->particles();
      const auto t0 = std::chrono::steady_clock::now();
      output::PlyPointCloud cloud(p.x);
      cloud.addVec3("vx", "vy", "vz", p.v);
      cloud.addFloat("n_p", p.count);
      cloud.addFloat("J", p.J);
      const std::string plyPath = (dir / "frame.ply").string();
      cloud.write(plyPath);
      const double plySeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      for (const char* method : {"density", "splat"}) {
        SurfaceSettings settings = scene.output.surface;
        settings.method = method;
        RenderOutputPaths paths{(dir / "surface.vdb").string(), (dir / "volume.vdb").string(),
                                (dir / "mesh.ply").string(), (dir / "mesh.obj").string()};
        MagnetizationInput magnetization;
        if (solver->magneticStage()) magnetization.grid = solver->magneticStage()->magnetization();
        const RenderOutputCost c =
            writeRenderOutputs(paths, p, scene.materialNames, settings, frames, solver->time(), magnetization);
        const auto size = [](const std::string& f) { return double(fs::file_size(f)); };
        std::printf("%-22s %9zu %-8s %9.3g %9.3g %9.3g %9.3g %9.3g %9zu %9.0fk %9.0fk %9.0fk %9.0fk\n",
                    scene.name.c_str(), p.size(), method, 1e3 * c.voxelSize, c.surface, c.mesh, c.volume, plySeconds,
                    c.triangles, size(paths.surface) / 1e3, size(paths.meshPly) / 1e3, size(paths.meshObj) / 1e3,
                    size(paths.volume) / 1e3);
        csv << scene.name << ',' << p.size() << ',' << method << ',' << c.voxelSize << ',' << c.surface << ','
            << c.mesh << ',' << c.volume << ',' << plySeconds << ',' << c.triangles << ',' << size(paths.surface)
            << ',' << size(paths.meshPly) << ',' << size(paths.meshObj) << ',' << size(paths.volume) << ','
            << size(plyPath) << '\n';
      }
    }
    fs::remove_all(dir);
    std::printf("CSV written to %s\n", csvPath.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-bench-render-outputs: %s\n", e.what());
    return 1;
  }
}
