// The distributed MPM (dist/mpm_partition.h, core's MpmSolver::setPartition)
// against the single-process solver, run under mpirun with 1, 2 and 4 ranks
// (tests labelled mpi). Every rank builds the same scene; rank 0 also runs it
// alone. Both take the same substeps; the distributed particles are then
// gathered on rank 0 and matched with the single-process ones by id.
//   elastic:  two Neo-Hookean blocks thrown across the grid's middle planes
//             (where 2 and 4 ranks split it), one onto a moving sphere
//             collider, the other onto the floor;
//   fluid:    a viscous column thrown down and sideways across the middle
//             planes;
//   magnetic: a Langevin ferrofluid block falling onto a sphere magnet (the
//             field solved on the gathered magnetic points, each time the
//             material has moved a quarter cell);
//   surface:  liquid drops with surface tension thrown across the planes
//             (the colour field summed over the ranks);
//   body:     a dynamic sphere thrown into a liquid pool that spans the
//             planes (its momentum exchange gathered from every rank); its
//             final velocity is compared too;
//   corner:   a drop with surface tension and a dynamic ball falling on it,
//             all in rank 0's box: the other ranks stay empty.
// Checks: the same particle count and total mass (to 1e-12 relative) after
// every migration, positions within 1e-10 of the box size and velocities
// within 1e-10 of the fastest particle's speed, the same number of field
// solves, and (with 2 or more ranks, except in the corner scene) particles
// did migrate. Prints the measured differences; exits 1 when one exceeds its
// bound. --nodes N sets the grid (default 33; the scenes are sized for 33).
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>

#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/rigid_body.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/dist/mpm_partition.h"
#include "lodestone/dist/petsc_session.h"

using namespace lodestone;

namespace {

int kNodes = 33;              // grid nodes per axis (--nodes)
constexpr double kDx = 0.01;  // m
constexpr double kBound = 1e-10;

double centre() { return 0.5 * (kNodes - 1) * kDx; }

std::unique_ptr<MpmSolver> makeScene(const std::string& scene) {
  MpmSettings s;
  s.grid.dx = kDx;
  s.grid.dims = {kNodes, kNodes, kNodes};
  s.fixedDt = 2e-4;  // s: the same substeps on every rank count
  s.reorderInterval = 7;
  auto solver = std::make_unique<MpmSolver>(s);
  const double c = centre();
  if (scene == "elastic") {
    const std::uint32_t m = solver->addMaterial(neoHookeanSolid(2e5, 0.3, 1000));
    EmitterSettings e;
    e.velocity = {1.5, 1.0, -0.5};
    solver->emit(EmitterShape::box(Pose::at({c - 0.06, c - 0.005, c + 0.03}), {0.03, 0.025, 0.02}), m, e);
    e.velocity = {-1.0, 0.8, -1.0};
    solver->emit(EmitterShape::sphere(Pose::at({c + 0.05, c - 0.04, c + 0.08}), 0.03), m, e);
    solver->addCollider(MpmCollider(
        ColliderShape::sphere(0.04),
        ColliderMotion::constantVelocity(Pose::at({c + 0.02, c + 0.02, c - 0.06}), {0, 0, 0.2}, {0, 0, 0})));
  } else if (scene == "fluid") {
    const std::uint32_t m = solver->addMaterial(viscousFluid(0.5, 2e4, 1000));
    EmitterSettings e;
    e.velocity = {0.8, 0.6, -1.0};
    solver->emit(EmitterShape::box(Pose::at({c - 0.03, c - 0.03, c - 0.02}), {0.06, 0.06, 0.12}), m, e);
  } else if (scene == "magnetic") {
    const std::uint32_t m = solver->addMaterial(viscousFluid(0.5, 2e4, 1200, paperMaterial()));
    solver->addMagnet(SphereMagnet(Pose::at({c, c, 0.06}), 0.03, {0, 0, magnetizationFromRemanence(1.2)}));
    EmitterSettings e;
    e.velocity = {0.6, -0.4, -0.3};
    solver->emit(EmitterShape::box(Pose::at({c - 0.01, c + 0.01, 0.17}), {0.04, 0.03, 0.02}), m, e);
  } else if (scene == "surface") {
    // Water-like drops with surface tension (sigma 0.5 N/m for a fast
    // capillary response at dx = 1 cm) thrown across the middle planes.
    MpmMaterial liquid = viscousFluid(0.01, 2e4, 1000);
    liquid.surfaceTension = 0.5;
    const std::uint32_t m = solver->addMaterial(liquid);
    EmitterSettings e;
    e.velocity = {1.2, 0.8, -0.6};
    solver->emit(EmitterShape::sphere(Pose::at({c - 0.03, c - 0.01, c + 0.01}), 0.04), m, e);
    e.velocity = {-0.8, -1.0, 0.4};
    solver->emit(EmitterShape::box(Pose::at({c + 0.05, c + 0.04, c - 0.05}), {0.03, 0.02, 0.03}), m, e);
  } else if (scene == "body") {
    // A dynamic sphere (600 kg/m^3) thrown down and sideways into a falling
    // liquid slab that spans the middle planes.
    const std::uint32_t m = solver->addMaterial(viscousFluid(0.05, 2e4, 1000));
    EmitterSettings e;
    e.velocity = {0, 0, -0.5};
    solver->emit(EmitterShape::box(Pose::at({c, c, 0.17}), {0.13, 0.13, 0.03}), m, e);
    const std::size_t ball = solver->addCollider(MpmCollider(
        ColliderShape::sphere(0.035),
        ColliderMotion::constantVelocity(Pose::at({c - 0.01, c + 0.01, 0.245}), {0.8, -0.6, -2.0}, {0, 0, 0})));
    RigidBodySettings b;
    b.density = 600;
    solver->collider(ball).setDynamics(b);
  } else if (scene == "corner") {
    // Everything in the lowest corner, inside rank 0's box: the other ranks
    // hold no particle and still take part in every exchange (the colour
    // sum of surface tension, the body's gathers, the reductions).
    MpmMaterial liquid = viscousFluid(0.01, 2e4, 1000);
    liquid.surfaceTension = 0.5;
    const std::uint32_t m = solver->addMaterial(liquid);
    solver->emit(EmitterShape::sphere(Pose::at({0.06, 0.06, 0.05}), 0.025), m, {});
    const std::size_t ball = solver->addCollider(
        MpmCollider(ColliderShape::sphere(0.015),
                    ColliderMotion::constantVelocity(Pose::at({0.06, 0.065, 0.1}), {0, 0, -1.5}, {0, 0, 0})));
    solver->collider(ball).setDynamics(RigidBodySettings{});
  } else {
    throw InvalidArgument(concat("unknown scene '", scene, "' (elastic, fluid, magnetic, surface, body, corner)"));
  }
  return solver;
}

struct Differences {
  double x = 0, v = 0, F = 0;  // relative, see the header (F: F and J)
  double vmax = 0;
};

Differences compare(const MpmParticles& a, const MpmParticles& b) {
  std::map<std::uint64_t, std::size_t> byId;
  for (std::size_t p = 0; p < b.size(); ++p) byId[b.id[p]] = p;
  Differences d;
  for (std::size_t p = 0; p < a.size(); ++p) d.vmax = std::max(d.vmax, norm(a.v[p]));
  for (std::size_t p = 0; p < a.size(); ++p) {
    const auto it = byId.find(a.id[p]);
    if (it == byId.end()) throw Error(concat("particle id ", a.id[p], " is missing from the distributed run"));
    const std::size_t q = it->second;
    d.x = std::max(d.x, norm(a.x[p] - b.x[q]) / ((kNodes - 1) * kDx));
    d.v = std::max(d.v, norm(a.v[p] - b.v[q]) / std::max(d.vmax, 1e-300));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) d.F = std::max(d.F, std::abs(a.F[p].m[r][c] - b.F[q].m[r][c]));
    d.F = std::max(d.F, std::abs(a.J[p] - b.J[q]));
  }
  return d;
}

int run(const std::string& scene, int substeps) {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  auto distributed = makeScene(scene);
  const std::size_t total = distributed->particles().size();
  const double mass = distributed->particles().totalMass();
  auto partition = std::make_shared<PetscMpmPartition>(MPI_COMM_WORLD, distributed->settings().grid);
  if (rank == 0) std::printf("%s: %s\n", scene.c_str(), partition->describe().c_str());
  distributed->setPartition(partition);
  int solves = 0;
  double worstCount = 0, worstMass = 0;
  for (int s = 0; s < substeps; ++s) {
    const MpmStepReport r = distributed->step(distributed->suggestedDt());
    solves += r.magneticSolved ? 1 : 0;
    double sums[2] = {double(distributed->particles().size()), distributed->particles().totalMass()};
    partition->sumOverRanks(sums, 2);
    worstCount = std::max(worstCount, std::abs(sums[0] - double(total)));
    worstMass = std::max(worstMass, std::abs(sums[1] - mass) / mass);
  }
  double sent = double(partition->sent());
  partition->sumOverRanks(&sent, 1);
  distributed->gatherParticlesToRoot();
  if (rank != 0) return 0;

  auto single = makeScene(scene);
  int singleSolves = 0;
  for (int s = 0; s < substeps; ++s) singleSolves += single->step(single->suggestedDt()).magneticSolved ? 1 : 0;
  const MpmParticles& a = single->particles();
  const MpmParticles& b = distributed->particles();
  const Differences d = compare(a, b);
  double body = 0;  // dynamic bodies' velocity difference, m/s
  const std::vector<RigidBodyReport> ra = single->rigidBodies(), rb = distributed->rigidBodies();
  for (std::size_t q = 0; q < ra.size() && q < rb.size(); ++q)
    body = std::max(body, norm(ra[q].velocity - rb[q].velocity) + norm(ra[q].angularVelocity - rb[q].angularVelocity));
  std::printf(
      "%s, %d ranks, %d substeps, %zu particles (%zu single, %zu gathered), %.0f migrations, %d field "
      "solves (%d single)\n",
      scene.c_str(), size, substeps, total, a.size(), b.size(), sent, solves, singleSolves);
  std::printf(
      "  max |x_d - x_s| / box = %.3g, max |v_d - v_s| / max|v| = %.3g (max |v| = %.3g m/s), max |F_d - F_s|, |J_d - "
      "J_s| "
      "= %.3g; particle count off by %.0f, mass by %.3g (relative) at worst over the substeps\n",
      d.x, d.v, d.vmax, d.F, worstCount, worstMass);
  bool ok = true;
  const auto fail = [&](const std::string& what) {
    std::printf("  FAIL: %s\n", what.c_str());
    ok = false;
  };
  if (a.size() != b.size() || a.size() != total) fail("particle counts differ");
  if (worstCount != 0) fail("particles were lost or duplicated in a migration");
  if (worstMass > 1e-12) fail("mass changed across migrations");
  if (d.x > kBound) fail(concat("positions differ by ", d.x, " of the box, more than ", kBound));
  if (d.v > kBound) fail(concat("velocities differ by ", d.v, " of the fastest, more than ", kBound));
  if (d.F > kBound) fail(concat("deformation gradients differ by ", d.F, ", more than ", kBound));
  if (solves != singleSolves) fail("the number of field solves differs");
  if (ra.size() != rb.size()) fail("the number of dynamic bodies differs");
  if (!ra.empty()) {
    std::printf("  dynamic body: velocity %.4g m/s, |v_d - v_s| + |w_d - w_s| = %.3g\n", norm(ra[0].velocity), body);
    if (body > kBound * std::max(1.0, norm(ra[0].velocity))) fail(concat("body velocities differ by ", body));
  }
  if (scene == "magnetic" && solves < 2) fail("the magnetic scene solved its field fewer than twice");
  if (size > 1 && sent < 1 && scene != "corner") fail("no particle migrated: the scene does not test migration");
  if (!(d.vmax > 0.1)) fail("the scene did not move");
  return ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  lodestone::PetscSession session(&argc, &argv);
  std::string scene = "elastic";
  int substeps = 50;
  for (int a = 1; a + 1 < argc; a += 2) {
    const std::string key = argv[a];
    if (key == "--scene")
      scene = argv[a + 1];
    else if (key == "--substeps")
      substeps = std::atoi(argv[a + 1]);
    else if (key == "--nodes")
      kNodes = std::atoi(argv[a + 1]);
  }
  try {
    return run(scene, substeps);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dist_mpm_check: %s\n", e.what());
    MPI_Abort(MPI_COMM_WORLD, 2);
    return 2;
  }
}
