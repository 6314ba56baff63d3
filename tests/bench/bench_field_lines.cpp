// lodestone-bench-field-lines: the price of the render-ready outputs of
// `lodestone run` per frame at default settings: field lines (tracing, and
// writing the .ply and .obj files) and previews (the particle preview with
// the lines drawn; a mesh preview of a surface-sized triangle mesh), for
// example scenes after their first frame. Prints a table and writes CSV.
// Not a test: timings are machine-dependent.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "field_line_output.h"
#include "lodestone/cli/command_line.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/stopwatch.h"
#include "lodestone/plugin/output/mesh_render.h"
#include "lodestone/plugin/scene.h"
#include "lodestone_test/sphere_mesh.h"
#include "preview.h"

using namespace lodestone;

namespace {

/// A latitude-longitude sphere of about `triangles` triangles around the
/// material's points (a stand-in for its surface mesh).
TriangleMesh sphereAround(const std::vector<Vec3d>& points, std::size_t triangles) {
  Vec3d lo = points.front(), hi = points.front();
  for (const Vec3d& p : points)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  const Vec3d c = 0.5 * (lo + hi);
  const double r = 0.5 * norm(hi - lo) / std::sqrt(3.0);
  const int rings = std::max(4, int(std::sqrt(double(triangles) / 4)));
  return test::latLongSphere(c, r, rings, 2 * rings);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::vector<std::string> scenes;
    std::string csvPath = "bench_render_outputs.csv";
    int repeats = 3;
    std::size_t meshTriangles = 200000;
    CLI::App app("lodestone-bench-field-lines: field lines and previews per frame, at default settings",
                 "lodestone-bench-field-lines");
    cli::helpLayout(app, 24);
    app.add_option("SCENE.json", scenes, "scenes (default: spike, slime_and_magnet, ferrofluid_3d)")->type_name("");
    cli::addNumber(app, "--repeats", repeats, "timings per output (the fastest is reported)")
        ->type_name("N")
        ->check(cli::wholeNumber(1, 100))
        ->default_str(cli::formatNumber(repeats));
    cli::addNumber(app, "--mesh-triangles", meshTriangles, "triangles of the mesh preview's stand-in surface")
        ->type_name("N")
        ->check(cli::wholeNumber(8, 100000000))
        ->default_str(cli::formatNumber(double(meshTriangles)));
    app.add_option("--csv", csvPath, "CSV output")->type_name("FILE")->capture_default_str();
    if (const std::optional<int> code = cli::parse(app, argc, argv)) return *code;
    if (scenes.empty())
      for (const char* s : {"spike", "slime_and_magnet", "ferrofluid_3d"})
        scenes.push_back(std::string(LODESTONE_SCENES_DIR) + "/" + s + ".json");
    std::ofstream csv(csvPath);
    require(bool(csv), "cannot write ", csvPath);
    csv << "scene,particles,magnets,lines,vertices,trace_ms,write_ms,ply_bytes,obj_bytes,preview_ms,"
           "preview_lines_ms,mesh_triangles,mesh_preview_ms\n";
    std::printf("%-18s %9s %5s %7s %9s %9s %9s %10s %10s %11s %12s\n", "scene", "particles", "lines", "vertices",
                "trace ms", "write ms", "ply KB", "preview ms", "+lines ms", "mesh tris", "mesh prev ms");
    const std::filesystem::path tmp = std::filesystem::temp_directory_path() / "lodestone_bench_render_outputs";
    std::filesystem::create_directories(tmp);
    for (const std::string& path : scenes) {
      const plugin::Scene scene = plugin::loadScene(path);
      auto solver = plugin::buildSolver(scene);
      solver->advanceFrame(scene.frameDuration());
      double trace = 1e300, write = 1e300, preview = 1e300, previewLines = 1e300, meshPreview = 1e300;
      std::vector<FieldLine> lines;
      for (int r = 0; r < repeats; ++r) {
        auto t = std::chrono::steady_clock::now();
        lines = examples::solverFieldLines(scene, *solver);
        trace = std::min(trace, secondsSince(t));
        t = std::chrono::steady_clock::now();
        examples::writeFieldLineFiles(tmp.string(), "0001", lines, scene, 1, solver->time());
        write = std::min(write, secondsSince(t));
        t = std::chrono::steady_clock::now();
        (void)examples::renderPreview(scene, *solver);
        preview = std::min(preview, secondsSince(t));
        t = std::chrono::steady_clock::now();
        (void)examples::renderPreview(scene, *solver, lines);
        previewLines = std::min(previewLines, secondsSince(t));
      }
      std::vector<Vec3d> material;
      const MpmParticles& p = solver->particles();
      for (std::size_t i = 0; i < p.size(); ++i)
        if (solver->materials()[p.material[i]].isMagnetic()) material.push_back(p.x[i]);
      if (material.empty()) material = p.x;
      const TriangleMesh mesh = sphereAround(material, meshTriangles);
      for (int r = 0; r < repeats; ++r) {
        const auto t = std::chrono::steady_clock::now();
        (void)examples::renderMeshPreview(scene, *solver, mesh, lines);
        meshPreview = std::min(meshPreview, secondsSince(t));
      }
      std::size_t vertices = 0;
      for (const FieldLine& l : lines) vertices += l.points.size();
      const auto ply = std::filesystem::file_size(tmp / "field_lines_0001.ply");
      const auto obj = std::filesystem::file_size(tmp / "field_lines_0001.obj");
      std::printf("%-18s %9zu %5zu %7zu %9.1f %9.1f %9.1f %10.1f %10.1f %11zu %12.1f\n", scene.name.c_str(), p.size(),
                  lines.size(), vertices, 1e3 * trace, 1e3 * write, ply / 1024.0, 1e3 * preview, 1e3 * previewLines,
                  mesh.triangles.size(), 1e3 * meshPreview);
      csv << scene.name << ',' << p.size() << ',' << solver->magnetCount() << ',' << lines.size() << ',' << vertices
          << ',' << 1e3 * trace << ',' << 1e3 * write << ',' << ply << ',' << obj << ',' << 1e3 * preview << ','
          << 1e3 * previewLines << ',' << mesh.triangles.size() << ',' << 1e3 * meshPreview << '\n';
    }
    std::printf("CSV written to %s\n", csvPath.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-bench-field-lines: %s\n", e.what());
    return 1;
  }
}
