// MPM step benchmark: the time of one MLS-MPM substep (P2G, grid update,
// G2P) for an elastic (Neo-Hookean) block and a viscous-fluid block, without
// magnetism, at 1e5 and 1e6 particles (8 per cell) on a 128^3 grid of the
// paper's spacing (dx = 7.8 mm). The block falls under gravity onto the
// floor with a small spin, so the particles move and the grid update has
// work to do. With --collider box or level_set a floor slab 1.5 cm thick
// (an analytic box, or its signed distance sampled every 2 mm) lies under the
// block, and each case runs with the collider projection off and on
// (MpmSettings::colliderProjection) in the same run: its price is the
// difference. With --bodies N1,N2,... a further table times a fluid block
// with N spheres (1 cm, 500 kg/m^3) resting in it, kinematic and dynamic in
// the same run: the price of the two-way coupling per substep is the
// difference. With --surface-tension SIGMA a further table times a resting
// fluid drop (no gravity) with sigma = 0 and with SIGMA (N/m) at the same dt:
// the price of the capillary stress (colour scatter and gradient pass) is the
// difference. With --slide V a further table times an elastic block (no
// gravity) at rest and sliding along x at V m/s at the same dt: the price of
// the motion, the grid's layouts after the block among it, is the
// difference. Prints tables and writes CSV. Not a test: timings are
// machine-dependent.
//
// Bandwidth. Each case also reports the bytes a substep must move at the
// least and the bandwidth that achieves, against a STREAM-like copy of the
// same number of bytes timed in the same run on the same threads. The bytes
// counted per particle: P2G reads x, v, C, J, mass, volume0, material (148
// B) and F for solids (72 B); G2P reads x and material (28 B), J for fluids
// or F for solids, and writes x, v, C, J (128 B) and F for solids: 312 B per
// fluid particle, 520 B per solid one. Per node of the active box: the
// node's mass and momentum written by P2G (32 B), read by the grid update
// (32 B), which writes the velocity (24 B) that G2P reads (24 B): 112 B.
// The binning's index arrays and the reordering are not counted (work the
// algorithm adds). The copy moves the same bytes, half read and half
// written, as STREAM counts them; the ratio is the substep's bandwidth over
// the copy's (1 would be a substep as fast as copying its data once).
// `lodestone-bench-mpm-step --help` lists the options.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include "lodestone/cli/command_line.h"

#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/sampled_sdf.h"
#include "lodestone/core/mpm/solver.h"

using namespace lodestone;

namespace {

constexpr double kDx = 7.8e-3;  // m, the grid spacing of every case

struct Timing {
  std::size_t particles = 0;
  int steps = 0;
  double dt = 0, total = 0, p2g = 0, binning = 0, grid = 0, g2p = 0;  // mean seconds per step
  // Bytes a substep must move (see the header).
  double bytes = 0;
};

/// Bytes one substep must move at the least (the count in the header).
double substepBytes(std::size_t particles, bool fluid, std::size_t activeNodes) {
  const double perParticle = fluid ? 312 : 520;
  return perParticle * double(particles) + 112.0 * double(activeNodes);
}

/// Best seconds of a parallel copy of bytes/2 bytes into another buffer
/// (STREAM's copy: bytes moved = 2 x the buffer) over `repeats` copies.
double copySeconds(double bytes, int repeats) {
  using Clock = std::chrono::steady_clock;
  const std::size_t n = std::size_t(bytes / 2 / sizeof(double));
  std::vector<double> from(n, 1.0), to(n, 0.0);  // touched: no first-touch faults in the timing
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<std::size_t>& b) {
      std::memcpy(to.data() + b.begin(), from.data() + b.begin(), (b.end() - b.begin()) * sizeof(double));
    });
    best = std::min(best, std::chrono::duration<double>(Clock::now() - t0).count());
  }
  require(to[n / 2] == 1.0, "bench: the copy did not copy");
  return best;
}

/// The floor slab of --collider: 1.5 cm thick, as wide as the domain, its top 2 cells above the floor.
MpmCollider floorSlab(const std::string& kind, const MpmSolver& solver) {
  const GridSpec& g = solver.settings().grid;
  const Vec3d lo = solver.domainLower(), hi = solver.domainUpper();
  const Vec3d half{0.5 * (hi.x - lo.x), 0.5 * (hi.y - lo.y), 0.0075};
  const Pose pose = Pose::at({0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), lo.z + 2 * g.dx - half.z});
  ColliderShape box = ColliderShape::box(half);
  if (kind == "box") return MpmCollider(box, ColliderMotion::fixed(pose));
  GridSpec sg;
  sg.dx = 0.002;
  sg.dims = {int(std::ceil(2 * half.x / sg.dx)) + 7, int(std::ceil(2 * half.y / sg.dx)) + 7,
             int(std::ceil(2 * half.z / sg.dx)) + 7};
  sg.origin = Vec3d{-0.5 * (sg.dims.i - 1) * sg.dx, -0.5 * (sg.dims.j - 1) * sg.dx, -0.5 * (sg.dims.k - 1) * sg.dx};
  std::vector<float> phi(sg.nodeCount());
  for (int k = 0; k < sg.dims.k; ++k)
    for (int j = 0; j < sg.dims.j; ++j)
      for (int i = 0; i < sg.dims.i; ++i) phi[sg.index(i, j, k)] = float(box.signedDistance(sg.nodePosition(i, j, k)));
  return MpmCollider(ColliderShape::levelSetShape(std::make_shared<const SampledSdf>(sg, std::move(phi), "slab")),
                     ColliderMotion::fixed(pose));
}

Timing run(bool fluid, double targetParticles, int steps, int nodes, int reorder, int age, const std::string& collider,
           bool projection, bool dense) {
  MpmSettings s;
  s.reorderInterval = reorder;
  s.denseGrid = dense;
  s.grid.dx = kDx;
  s.grid.dims = {nodes, nodes, nodes};
  s.colliderProjection = projection;
  MpmSolver solver(s);
  if (collider != "none") solver.addCollider(floorSlab(collider, solver));
  const std::uint32_t m = solver.addMaterial(fluid ? viscousFluid(1.0, 1e5, 1000) : neoHookeanSolid(1e5, 0.3, 1000));
  // A cube of n cells per side at 8 particles per cell.
  const int n = std::max(2, int(std::lround(std::cbrt(targetParticles / 8.0))));
  const double half = 0.5 * n * s.grid.dx;
  const Vec3d lo = solver.domainLower(), hi = solver.domainUpper();
  require(2 * half < hi.z - lo.z, "bench: ", targetParticles, " particles do not fit a ", nodes, "^3 grid");
  const Vec3d centre{0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), hi.z - half - 2 * s.grid.dx};
  EmitterSettings e;
  e.angularVelocity = {0, 0, 1.0};  // rad/s
  e.velocity = {0, 0, -1.0};        // m/s
  solver.emit(EmitterShape::box(Pose::at(centre), {half, half, half}), m, e);
  Timing t;
  t.particles = solver.particles().size();
  const double dt = solver.suggestedDt();
  // Warm-up (first-touch allocation, caches), then `age` more substeps so the
  // particles have moved away from their emission order.
  for (int w = 0; w < 2 + age; ++w) solver.step(dt);
  for (int k = 0; k < steps; ++k) {
    const MpmStepReport r = solver.step(dt);
    t.total += r.secondsTotal;
    t.p2g += r.secondsP2G;
    t.binning += r.secondsBinning;
    t.grid += r.secondsGridUpdate;
    t.g2p += r.secondsG2P;
  }
  t.steps = steps;
  t.dt = dt;
  const MpmGrid& g = solver.grid();
  const std::size_t activeNodes = std::size_t(g.activeHi().i - g.activeLo().i) *
                                  std::size_t(g.activeHi().j - g.activeLo().j) *
                                  std::size_t(g.activeHi().k - g.activeLo().k);
  t.bytes = substepBytes(t.particles, fluid, activeNodes);
  t.total /= steps;
  t.p2g /= steps;
  t.binning /= steps;
  t.grid /= steps;
  t.g2p /= steps;
  return t;
}

/// Mean seconds per substep of a fluid block (about `particles`) with
/// `bodies` spheres of 1 cm radius on a lattice inside it, dynamic or kinematic.
double bodiesRun(double particles, int bodies, bool dynamic, int steps, int nodes) {
  MpmSettings s;
  s.grid.dx = kDx;
  s.grid.dims = {nodes, nodes, nodes};
  MpmSolver solver(s);
  const std::uint32_t m = solver.addMaterial(viscousFluid(1.0, 1e5, 1000));
  const int n = std::max(2, int(std::lround(std::cbrt(particles / 8.0))));
  const double half = 0.5 * n * s.grid.dx;
  const Vec3d lo = solver.domainLower(), hi = solver.domainUpper();
  const Vec3d centre{0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), lo.z + half};
  solver.emit(EmitterShape::box(Pose::at(centre), {half, half, half}), m, {});
  const int per = std::max(1, int(std::ceil(std::cbrt(double(bodies)))));
  RigidBodySettings b;
  b.density = 500;
  for (int k = 0; k < bodies; ++k) {
    const Vec3d f{(k % per + 0.5) / per, (k / per % per + 0.5) / per, (k / (per * per) + 0.5) / per};
    const Vec3d at = centre + 2 * half * (f - Vec3d{0.5, 0.5, 0.5});
    MpmCollider c(ColliderShape::sphere(0.01), ColliderMotion::fixed(Pose::at(at)));
    if (dynamic) c.setDynamics(b);
    solver.addCollider(c);
  }
  const double dt = solver.suggestedDt();
  for (int w = 0; w < 2; ++w) solver.step(dt);
  double total = 0;
  for (int k = 0; k < steps; ++k) total += solver.step(dt).secondsTotal;
  return total / steps;
}

/// Mean seconds per substep of a resting fluid drop (a sphere of about
/// `particles`, no gravity) with surface tension sigma (N/m), at the substep
/// dt (s); P2G (including the capillary passes) in *p2g.
double dropRun(double particles, double sigma, double dt, int steps, int nodes, double* p2g) {
  MpmSettings s;
  s.grid.dx = kDx;
  s.grid.dims = {nodes, nodes, nodes};
  s.gravity = {0, 0, 0};
  MpmSolver solver(s);
  MpmMaterial water = viscousFluid(1.0, 1e5, 1000);
  water.surfaceTension = sigma;
  const std::uint32_t m = solver.addMaterial(water);
  const double radius = std::cbrt(3 * particles / (8 * 4 * 3.14159265358979)) * s.grid.dx;
  const Vec3d lo = solver.domainLower(), hi = solver.domainUpper();
  require(2 * radius < hi.z - lo.z, "bench: a drop of ", particles, " particles does not fit a ", nodes, "^3 grid");
  solver.emit(EmitterShape::sphere(Pose::at(0.5 * (lo + hi)), radius), m, {});
  for (int w = 0; w < 2; ++w) solver.step(dt);
  double total = 0;
  *p2g = 0;
  for (int k = 0; k < steps; ++k) {
    const MpmStepReport r = solver.step(dt);
    total += r.secondsTotal;
    *p2g += r.secondsP2G;
  }
  *p2g /= steps;
  return total / steps;
}

/// Mean seconds per substep of an elastic block (about `particles`, no
/// gravity) sliding along x at `speed` (m/s) from the domain's low x side, at
/// the substep dt (s), and that dt in *dtOut: the solver's grid, laid out
/// over the material's box, is laid out anew each time the block leaves it.
double slideRun(double particles, double speed, int steps, int nodes, bool dense, double* dtOut) {
  MpmSettings s;
  s.grid.dx = kDx;
  s.grid.dims = {nodes, nodes, nodes};
  s.gravity = {0, 0, 0};
  s.denseGrid = dense;
  MpmSolver solver(s);
  const std::uint32_t m = solver.addMaterial(neoHookeanSolid(1e5, 0.3, 1000));
  const int n = std::max(2, int(std::lround(std::cbrt(particles / 8.0))));
  const double half = 0.5 * n * s.grid.dx;
  const Vec3d lo = solver.domainLower(), hi = solver.domainUpper();
  require(2 * half < 0.6 * (hi.x - lo.x), "bench: a sliding block of ", particles, " particles does not fit a ", nodes,
          "^3 grid");
  EmitterSettings e;
  e.velocity = {speed, 0, 0};
  solver.emit(EmitterShape::box(Pose::at({lo.x + half + 4 * s.grid.dx, 0.5 * (lo.y + hi.y), 0.5 * (lo.z + hi.z)}),
                                {half, half, half}),
              m, e);
  // The slowest speed's dt for every speed, so that only the motion differs.
  const double dt = std::min(solver.suggestedDt(), 0.25 * s.grid.dx / 20.0);
  for (int w = 0; w < 2; ++w) solver.step(dt);
  double total = 0;
  for (int k = 0; k < steps; ++k) total += solver.step(dt).secondsTotal;
  require(solver.particles().size() > 0, "bench: the sliding block left the grid");
  *dtOut = dt;
  return total / steps;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::vector<double> counts{1e5, 1e6};
    int steps = 20, nodes = 128, threads = 0, reorder = MpmSettings{}.reorderInterval, age = 0;
    bool dense = false;
    std::string csvPath = "bench_mpm_step.csv", collider = "none";
    std::vector<double> bodies;
    double sigma = 0, slide = 0;
    CLI::App app("lodestone-bench-mpm-step: times one MLS-MPM substep (no magnetism)", "lodestone-bench-mpm-step");
    cli::helpLayout(app, 28);
    cli::addNumberList(app, "--particles", counts, "target particle counts, 8 per cell (each 8..1e9)");
    cli::addNumber(app, "--steps", steps, "timed substeps per case (the default amortizes one reorder)")
        ->type_name("N")
        ->check(cli::wholeNumber(1, 100000))
        ->default_str(cli::formatNumber(steps));
    cli::addNumber(app, "--grid", nodes, "nodes per axis (dx = 7.8 mm)")
        ->type_name("N")
        ->check(cli::wholeNumber(16, 1024))
        ->default_str(cli::formatNumber(nodes));
    cli::addNumber(app, "--threads", threads, "worker threads (0: all cores)")
        ->type_name("N")
        ->check(cli::wholeNumber(0, 1024))
        ->default_str(cli::formatNumber(threads));
    cli::addNumber(app, "--reorder", reorder, "MpmSettings::reorderInterval (0: never sort particles by cell)")
        ->type_name("N")
        ->check(cli::wholeNumber(0))
        ->default_str(cli::formatNumber(reorder));
    cli::addNumber(app, "--age", age, "untimed substeps before timing (0: particles in emission order)")
        ->type_name("N")
        ->check(cli::wholeNumber(0))
        ->default_str(cli::formatNumber(age));
    app.add_option("--collider", collider, "a floor slab under the block: none, box or level_set (each case then "
                   "runs with the collider projection off and on)")
        ->check(CLI::IsMember({"none", "box", "level_set"}))
        ->capture_default_str();
    cli::addNumberList(app, "--bodies", bodies,
                       "also time a fluid block with this many 1 cm spheres in it, kinematic and dynamic (e.g. 1,20,100)");
    cli::addNumber(app, "--surface-tension", sigma,
                   "also time a resting fluid drop without and with this surface tension (N/m, in (0, 10])")
        ->type_name("SIGMA");
    cli::addNumber(app, "--slide", slide,
                   "also time an elastic block sliding along x at this speed (m/s, in (0, 20]) against the same "
                   "block at rest, at one dt")
        ->type_name("V");
    app.add_flag("--dense", dense, "hold the MPM grid whole (MpmSettings::denseGrid) instead of the runs the particles reach");
    app.add_option("--csv", csvPath, "CSV output")->type_name("FILE")->capture_default_str();
    if (const std::optional<int> code = cli::parse(app, argc, argv)) return *code;
    for (double c : counts) require(c >= 8 && c <= 1e9, "--particles: ", c, " is not in 8..1e9");

    std::ofstream csv(csvPath);
    require(bool(csv), "cannot write ", csvPath);
    csv << "material,particles,grid_nodes_per_axis,steps,age_steps,reorder_interval,collider,collider_projection,dt_s,"
           "ms_per_step,ms_p2g,ms_binning,ms_grid_update,ms_g2p,ns_per_particle_step,threads,bytes_per_step,"
           "gb_per_s,copy_gb_per_s,bandwidth_ratio,dense_grid\n";
    if (threads == 0) threads = tbb::info::default_concurrency();
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    std::printf(
        "Lodestone MPM step benchmark (%d threads, %d^3 grid, dx = 7.8 mm, %d timed substeps after %d, "
        "reorder interval %d%s)\n",
        threads, nodes, steps, age + 2, reorder, dense ? ", grid held whole" : "");
    std::printf("%-8s %10s %10s %10s %9s %9s %9s %9s %9s %10s %7s %7s %6s\n", "material", "particles", "projection",
                "dt s", "ms/step", "P2G", "(binning)", "grid", "G2P", "ns/p/step", "GB/s", "copy", "ratio");
    for (double c : counts)
      for (int fluid = 0; fluid < 2; ++fluid)
        for (int projection = collider == "none" ? 1 : 0; projection < 2; ++projection) {
          const Timing t = run(fluid != 0, c, steps, nodes, reorder, age, collider, projection != 0, dense);
          const char* name = fluid ? "fluid" : "elastic";
          const char* proj = collider == "none" ? "-" : projection ? "on" : "off";
          const double ns = 1e9 * t.total / double(t.particles);
          const double gbs = t.bytes / t.total * 1e-9, copyGbs = t.bytes / copySeconds(t.bytes, 5) * 1e-9;
          std::printf("%-8s %10zu %10s %10.3g %9.2f %9.2f %9.2f %9.2f %9.2f %10.1f %7.1f %7.1f %6.2f\n", name,
                      t.particles, proj, t.dt, 1e3 * t.total, 1e3 * t.p2g, 1e3 * t.binning, 1e3 * t.grid, 1e3 * t.g2p,
                      ns, gbs, copyGbs, gbs / copyGbs);
          std::fflush(stdout);
          csv << name << ',' << t.particles << ',' << nodes << ',' << t.steps << ',' << age << ',' << reorder << ','
              << collider << ',' << proj << ',' << t.dt << ',' << 1e3 * t.total << ',' << 1e3 * t.p2g << ','
              << 1e3 * t.binning << ',' << 1e3 * t.grid << ',' << 1e3 * t.g2p << ',' << ns << ',' << threads << ','
              << t.bytes << ',' << gbs << ',' << copyGbs << ',' << gbs / copyGbs << ',' << int(dense) << '\n';
        }
    if (!bodies.empty()) {
      std::printf("\nrigid bodies in a fluid block of %.3g particles: ms per substep\n%8s %12s %12s %10s\n", counts.front(),
                  "bodies", "kinematic", "dynamic", "coupling");
      for (double nb : bodies) {
        require(nb >= 1 && nb <= 10000 && nb == std::floor(nb), "--bodies: ", nb, " is not a whole number in 1..10000");
        const double k = bodiesRun(counts.front(), int(nb), false, steps, nodes);
        const double d = bodiesRun(counts.front(), int(nb), true, steps, nodes);
        std::printf("%8d %12.2f %12.2f %9.1f%%\n", int(nb), 1e3 * k, 1e3 * d, 100 * (d / k - 1));
        std::fflush(stdout);
        csv << "fluid+bodies," << counts.front() << ',' << nodes << ',' << steps << ",0," << reorder << ",spheres:" << nb
            << ",kinematic,0," << 1e3 * k << ",,,,,," << threads << '\n';
        csv << "fluid+bodies," << counts.front() << ',' << nodes << ',' << steps << ",0," << reorder << ",spheres:" << nb
            << ",dynamic,0," << 1e3 * d << ",,,,,," << threads << '\n';
      }
    }
    if (slide != 0) {
      require(std::isfinite(slide) && slide > 0 && slide <= 20, "--slide: ", slide, " m/s is not in (0, 20]");
      std::printf("\nan elastic block sliding along x, no gravity: ms per substep%s\n%10s %10s %14s %10s %10s\n",
                  dense ? " (grid held whole)" : "", "particles", "m/s", "cells/substep", "ms/step", "ratio");
      for (double c : counts) {
        double dt = 0;
        const double t0 = slideRun(c, 0.0, steps, nodes, dense, &dt);
        const double t1 = slideRun(c, slide, steps, nodes, dense, &dt);
        std::printf("%10.3g %10s %14s %10.2f\n%10s %10.3g %14.3f %10.2f %9.2fx\n", c, "0", "0", 1e3 * t0, "", slide,
                    slide * dt / kDx, 1e3 * t1, t1 / t0);
        std::fflush(stdout);
        csv << "slide," << c << ',' << nodes << ',' << steps << ",0," << reorder << ",speed:0,-," << dt << ','
            << 1e3 * t0 << ",,,,,," << threads << ",,,,," << int(dense) << '\n';
        csv << "slide," << c << ',' << nodes << ',' << steps << ",0," << reorder << ",speed:" << slide << ",-," << dt
            << ',' << 1e3 * t1 << ",,,,,," << threads << ",,,,," << int(dense) << '\n';
      }
    }
    if (sigma != 0) {
      require(std::isfinite(sigma) && sigma > 0 && sigma <= kMaxSurfaceTension, "--surface-tension: ", sigma,
              " N/m is not in (0, ", kMaxSurfaceTension, "]");
      const double dt = 1e-5;  // s, below every limit of both cases
      std::printf("\nsurface tension: a resting drop at dt = %.3g s, ms per substep\n%10s %10s %10s %10s %8s\n", dt,
                  "particles", "sigma N/m", "ms/step", "P2G", "ratio");
      for (double c : counts) {
        double p0 = 0, p1 = 0;
        const double t0 = dropRun(c, 0, dt, steps, nodes, &p0);
        const double t1 = dropRun(c, sigma, dt, steps, nodes, &p1);
        std::printf("%10.3g %10s %10.2f %10.2f\n%10s %10.3g %10.2f %10.2f %7.2fx\n", c, "0", 1e3 * t0, 1e3 * p0, "",
                    sigma, 1e3 * t1, 1e3 * p1, t1 / t0);
        std::fflush(stdout);
        csv << "drop," << c << ',' << nodes << ',' << steps << ",0," << reorder << ",sigma:0,-," << dt << ','
            << 1e3 * t0 << ',' << 1e3 * p0 << ",,,,," << threads << '\n';
        csv << "drop," << c << ',' << nodes << ',' << steps << ",0," << reorder << ",sigma:" << sigma << ",-," << dt
            << ',' << 1e3 * t1 << ',' << 1e3 * p1 << ",,,,," << threads << '\n';
      }
    }
    std::printf("CSV written to %s\n", csvPath.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-bench-mpm-step: %s\n", e.what());
    return 1;
  }
}
