// Separate patches of material solved on their own grids and coupled
// through their far fields (stage/magnetic_patches.h), against one solve on
// a box around all of them: two spheres in a uniform field (their force on
// each other is all there is) and a sphere beside a cube above a magnet;
// the grouping of points into patches (planner/material_patches.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/planner/material_patches.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/core/stage/far_field.h"
#include "lodestone/core/stage/magnetic_patches.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone_test/scenes.h"

using namespace lodestone;

namespace {
constexpr double kDx = 0.005;  // m
constexpr int kPad = 11;       // the planner's: stencil 3 + margin 8 cells

struct Body {
  std::vector<Vec3d> x;
  std::vector<double> count;
};

// Points at 8 per cell (jittered) inside `inside`, within the box centre +- r.
template <typename Inside>
Body fill(const Vec3d& centre, double r, double n0, unsigned seed, Inside inside) {
  Body b;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  const double h = kDx / 2;
  for (double z = -r; z <= r; z += h)
    for (double y = -r; y <= r; y += h)
      for (double x = -r; x <= r; x += h) {
        const Vec3d p = Vec3d{x, y, z} + 0.25 * h * Vec3d{U(rng), U(rng), U(rng)};
        if (inside(p)) {
          b.x.push_back(centre + p);
          b.count.push_back(n0 * h * h * h);
        }
      }
  return b;
}
Body ballAt(const Vec3d& c, double r, double n0, unsigned seed) {
  return fill(c, r, n0, seed, [r](const Vec3d& p) { return norm2(p) < r * r; });
}
Body cubeAt(const Vec3d& c, double half, double n0, unsigned seed) {
  return fill(c, half, n0, seed, [half](const Vec3d& p) {
    return std::fabs(p.x) < half && std::fabs(p.y) < half && std::fabs(p.z) < half;
  });
}

// A grid of spacing kDx on the lattice through the origin covering [lo, hi].
GridSpec gridCovering(const Vec3d& lo, const Vec3d& hi) {
  GridSpec g;
  g.dx = kDx;
  int a[3], b[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = int(std::floor(lo[k] / kDx));
    b[k] = int(std::ceil(hi[k] / kDx));
  }
  g.origin = {a[0] * kDx, a[1] * kDx, a[2] * kDx};
  g.dims = {b[0] - a[0] + 1, b[1] - a[1] + 1, b[2] - a[2] + 1};
  return g;
}

struct Comparison {
  std::vector<Vec3d> boxForce, patchForce;  // per body, N
  double fieldError = 0;                    // max |H_patch - H_box| / max |H_box| at the points
  std::vector<Vec3d> moments;               // per patch: its material's dipole moment, A m^2
  MagneticPatchReport report;
};

// Solves bodies a and b once on a box around both (grid `box`) and once as
// the patches findMaterialPatches makes of them; forces per body
// (particleForces, summed) and the field at the points.
Comparison compare(const GridSpec& box, const std::vector<Body>& bodies, const MagneticMaterial& mat,
                   const FieldSource& src, const MagneticPatchSettings& ps = {}) {
  MagneticStageSettings st;
  st.solve.tolerance = 1e-9;
  std::vector<Vec3d> x;
  std::vector<double> n;
  std::vector<std::size_t> bodyOf;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    x.insert(x.end(), bodies[b].x.begin(), bodies[b].x.end());
    n.insert(n.end(), bodies[b].count.begin(), bodies[b].count.end());
    bodyOf.insert(bodyOf.end(), bodies[b].x.size(), b);
  }
  Comparison c;
  c.boxForce.assign(bodies.size(), Vec3d{});
  c.patchForce.assign(bodies.size(), Vec3d{});
  MagneticForceStage whole(box, mat, st);
  const MagneticStageReport rep = whole.run({x.data(), n.data(), x.size()}, src, 0.0);
  EXPECT_TRUE(rep.converged()) << rep.summary();
  std::vector<Vec3d> f(x.size()), H(x.size());
  whole.particleForces({x.data(), n.data(), x.size()}, f.data());
  whole.sampleField(x.data(), x.size(), H.data());
  for (std::size_t p = 0; p < x.size(); ++p) c.boxForce[bodyOf[p]] += f[p];

  const MaterialPatches found = findMaterialPatches(box, x.data(), x.size(), kPad);
  EXPECT_EQ(found.grids.size(), bodies.size());
  MagneticPatches patches(found.grids, mat, st, ps);
  std::vector<std::vector<Vec3d>> px(found.grids.size());
  std::vector<std::vector<double>> pn(found.grids.size());
  std::vector<std::vector<std::size_t>> pid(found.grids.size());
  for (std::size_t p = 0; p < x.size(); ++p) {
    px[found.patchOf[p]].push_back(x[p]);
    pn[found.patchOf[p]].push_back(n[p]);
    pid[found.patchOf[p]].push_back(p);
  }
  std::vector<ParticleView> views;
  for (std::size_t q = 0; q < px.size(); ++q) views.push_back({px[q].data(), pn[q].data(), px[q].size()});
  c.report = patches.run(views, src, 0.0);
  for (std::size_t q = 0; q < px.size(); ++q) {
    Vec3d m;
    for (const Multipole& b : patches.moments(q)) m += b.dipole;
    c.moments.push_back(m);
  }
  double scale = 0;
  for (const Vec3d& h : H) scale = std::max(scale, norm(h));
  for (std::size_t q = 0; q < px.size(); ++q) {
    std::vector<Vec3d> fq(px[q].size()), Hq(px[q].size());
    patches.particleForces(q, views[q], fq.data());
    patches.stage(q).sampleField(px[q].data(), px[q].size(), Hq.data());
    for (std::size_t m = 0; m < px[q].size(); ++m) {
      c.patchForce[bodyOf[pid[q][m]]] += fq[m];
      c.fieldError = std::max(c.fieldError, norm(Hq[m] - H[pid[q][m]]) / scale);
    }
  }
  return c;
}

double relative(const Vec3d& a, const Vec3d& b) { return norm(a - b) / norm(b); }
}  // namespace

TEST(MagneticPatches, TwoSpheresInAUniformFieldPullEachOtherAsTheirMomentsSay) {
  // In a uniform field along the line of centres a lone sphere feels no
  // force: each sphere's force is the other's far field acting on it, so
  // the coupling is all that is measured. Spheres of radius 6 cells, 36
  // cells apart (surface to surface); the box around both has 83 x 35 x 35
  // nodes, each patch 35^3. Outside a uniformly magnetized sphere the
  // field is its dipole's, and the force on a uniformly magnetized sphere
  // in a harmonic field is mu0 (m . grad) H at its centre: coaxial dipoles
  // at distance d attract with F = 3 mu0 m_a m_b / (2 pi d^4), with the
  // moments the patches' solves hold (the mutual induction changes them by
  // (a/d)^3 chi ~ 1e-3).
  const MagneticMaterial mat = paperMaterial();
  const double r = 0.03, d = 0.24;
  const std::vector<Body> bodies{ballAt({-d / 2, 0, 0}, r, mat.numberDensity, 1),
                                 ballAt({d / 2, 0, 0}, r, mat.numberDensity, 2)};
  const GridSpec box = gridCovering({-0.15 - kPad * kDx, -r - kPad * kDx, -r - kPad * kDx},
                                    {0.15 + kPad * kDx, r + kPad * kDx, r + kPad * kDx});
  const UniformField src({3e4, 0, 0});
  // Each sphere alone (one round from no far field): the force its own
  // discretization leaves on it (jittered points, a patch not centred on
  // it), ~1e-5 of its magnetic stress M^2 mu0 a^2; the pull is what the
  // coupling adds to it.
  MagneticPatchSettings alone;
  alone.maxRounds = 1;
  const Comparison uncoupled = compare(box, bodies, mat, src, alone);
  EXPECT_FALSE(uncoupled.report.couplingConverged);
  const Comparison c = compare(box, bodies, mat, src);
  ASSERT_TRUE(c.report.converged()) << c.report.summary();
  ASSERT_EQ(c.moments.size(), 2u);
  const double closed = 3 * kMu0 * c.moments[0].x * c.moments[1].x / (2 * kPi * std::pow(d, 4));
  const Vec3d pullA = c.patchForce[0] - uncoupled.patchForce[0], pullB = c.patchForce[1] - uncoupled.patchForce[1];
  std::printf("two spheres: moments %.6g, %.6g A m^2; pull from the moments %.6g N; patches %.6g and %.6g N "
              "(relative %.3g, %.3g; alone %.3g and %.3g N); one box %.6g N (relative to the moments' %.3g); "
              "field difference %.3g; %d rounds, coupling change %.3g\n",
              c.moments[0].x, c.moments[1].x, closed, pullA.x, -pullB.x, pullA.x / closed - 1, -pullB.x / closed - 1,
              norm(uncoupled.patchForce[0]), norm(uncoupled.patchForce[1]), c.boxForce[0].x,
              c.boxForce[0].x / closed - 1, c.fieldError, c.report.rounds, c.report.couplingChange);
  EXPECT_NEAR(pullA.x, closed, 0.005 * closed);
  EXPECT_NEAR(-pullB.x, closed, 0.005 * closed);
  EXPECT_LT(std::hypot(pullA.y, pullA.z), 0.005 * closed);
  EXPECT_LT(std::hypot(pullB.y, pullB.z), 0.005 * closed);
  // Without the coupling the pull is missing altogether.
  EXPECT_LT(std::fabs(uncoupled.patchForce[0].x), 0.05 * closed);
  // The one-box solve takes the same pull from the discrete Maxwell stress
  // between the spheres, first order in dx: 7% low at 6 cells a radius.
  EXPECT_NEAR(c.boxForce[0].x, closed, 0.1 * closed);
  // Fields: the solve tolerance (1e-9) plus the far field's truncation.
  EXPECT_LT(c.fieldError, 1e-3);
  EXPECT_GE(c.report.rounds, 2);
}

TEST(MagneticPatches, ASphereBesideACubeAboveAMagnetFeelsWhatItFeelsInOneBox) {
  // The magnet's gradient pulls both down; each also pulls on the other.
  const MagneticMaterial mat = paperMaterial();
  const double r = 0.025;
  const std::vector<Body> bodies{ballAt({-0.1, 0, 0}, r, mat.numberDensity, 3),
                                 cubeAt({0.1, 0.01, 0}, r, mat.numberDensity, 4)};
  const GridSpec box = gridCovering({-0.125 - kPad * kDx, -r - kPad * kDx, -r - kPad * kDx},
                                    {0.125 + kPad * kDx, 0.01 + r + kPad * kDx, r + kPad * kDx});
  const SphereMagnet magnet(Pose::at({0, 0, -0.16}), 0.05, {0, 0, 8e5});
  const Comparison c = compare(box, bodies, mat, magnet);
  ASSERT_TRUE(c.report.converged()) << c.report.summary();
  for (int b = 0; b < 2; ++b) {
    std::printf("%s: box force (%.5g, %.5g, %.5g) N, patches (%.5g, %.5g, %.5g) N, relative %.3g\n",
                b ? "cube" : "sphere", c.boxForce[b].x, c.boxForce[b].y, c.boxForce[b].z, c.patchForce[b].x,
                c.patchForce[b].y, c.patchForce[b].z, relative(c.patchForce[b], c.boxForce[b]));
    EXPECT_LT(c.boxForce[b].z, 0.0);
    EXPECT_LT(relative(c.patchForce[b], c.boxForce[b]), 0.005);
  }
  std::printf("sphere and cube: field error %.3g, %d rounds\n", c.fieldError, c.report.rounds);
  EXPECT_LT(c.fieldError, 1e-3);
}

TEST(SampledFarField, IsWithinItsBoundOfTheSumAndExactWhenTheBlocksAreNear) {
  // 27 blocks of a magnetized cube (8-cell blocks, dipoles of a few A m^2
  // leaning every way) beside a 30^3 grid: their centres 64 cells away, the
  // field is sampled every 4 cells and interpolated, within 1.5 (h/d)^2 of
  // the largest far field over the grid; 24 cells away it is summed exactly.
  const GridSpec g{{0, 0, 0}, kDx, {30, 30, 30}};
  for (const double gap : {60.0, 20.0}) {
    std::vector<Multipole> blocks;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(-1, 1);
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
          Multipole m;
          m.centre = Vec3d{(29 + gap + 4 + 8 * i) * kDx, (11 + 8 * j) * kDx, (11 + 8 * k) * kDx};
          m.dipole = Vec3d{0.3 * U(rng), 0.3 * U(rng), 2 + 0.3 * U(rng)};
          blocks.push_back(m);
        }
    const SampledFarField sampled(blocks, g);
    double largest = 0, worst = 0;
    std::size_t compared = 0;
    const auto compare = [&](const Vec3d& x) {
      const Vec3d exact = farFieldOf(blocks, x);
      largest = std::max(largest, norm(exact));
      worst = std::max(worst, norm(sampled.at(x) - exact));
      ++compared;
    };
    for (int k = 0; k < 30; ++k)
      for (int j = 0; j < 30; ++j)
        for (int i = 0; i < 30; ++i) compare(g.nodePosition(i, j, k));
    for (int q = 0; q < 2000; ++q)  // between the nodes, and up to a cell beyond the box
      compare(Vec3d{(14.5 + 15.5 * U(rng)) * kDx, (14.5 + 15.5 * U(rng)) * kDx, (14.5 + 15.5 * U(rng)) * kDx});
    const double d = distanceToBlocks(g, blocks), h = sampled.spacing();
    std::printf("blocks %.0f cells from the grid: lattice %.0f cells, worst %.3g of the largest far field %.4g A/m "
                "(bound 1.5 (h/d)^2 = %.3g), %zu points\n",
                d / kDx, h / kDx, worst / largest, largest, 1.5 * (h / d) * (h / d), compared);
    EXPECT_NEAR(d, (gap + 4) * kDx, 1e-12);
    if (gap == 60.0) {
      EXPECT_NEAR(h, 4 * kDx, 1e-12);  // floor(64 / 16) cells
      EXPECT_GT(worst, 0.0);
      EXPECT_LT(worst, 1.5 * (h / d) * (h / d) * largest);
    } else {
      EXPECT_EQ(h, 0.0);
      EXPECT_EQ(worst, 0.0);
    }
  }
}

TEST(MaterialPatches, GroupsTouchingPointsAndMergesPatchesThatWouldMeet) {
  GridSpec g;
  g.dx = 0.01;
  g.dims = {200, 50, 50};
  std::vector<Vec3d> x;
  // A line of points 0.5 pad apart (one group), then one point 30 cells
  // further (its own patch: the widened boxes lie 6 cells apart), then one
  // 21.5 cells beyond that, in a cell of edge pad that does not touch the
  // previous point's: its widened box (pad 11) meets that point's, so the
  // two are merged.
  for (int s = 0; s < 10; ++s) x.push_back({0.2025 + 0.055 * s, 0.25, 0.25});
  x.push_back({0.2025 + 0.055 * 9 + 0.30, 0.25, 0.25});
  x.push_back({0.2025 + 0.055 * 9 + 0.515, 0.25, 0.25});
  const MaterialPatches p = findMaterialPatches(g, x.data(), x.size(), kPad);
  ASSERT_EQ(p.grids.size(), 2u);
  for (int s = 0; s < 10; ++s) EXPECT_EQ(p.patchOf[std::size_t(s)], 0u);
  EXPECT_EQ(p.patchOf[10], 1u);
  EXPECT_EQ(p.patchOf[11], 1u);
  // Each grid is its points' box plus the pad, on the full grid's lattice.
  EXPECT_NEAR(p.grids[0].origin.x, 0.2 - kPad * 0.01, 1e-12);
  EXPECT_EQ(p.grids[0].dims.i, int(std::lround(0.055 * 9 / 0.01)) + 2 * kPad + 1);
  EXPECT_EQ(p.grids[0].dims.j, 2 * kPad + 1);
  EXPECT_THROW(findMaterialPatches(g, x.data(), x.size(), 0), InvalidArgument);
  EXPECT_THROW(findMaterialPatches(g, x.data(), 0, kPad), InvalidArgument);
}

TEST(MagneticPatches, RefuseOverlappingPatchesAndAShieldWall) {
  const MagneticMaterial mat = paperMaterial();
  GridSpec a;
  a.dx = kDx;
  a.dims = {10, 10, 10};
  GridSpec b = a;
  b.origin = {9 * kDx, 0, 0};  // shares a face of nodes with a
  try {
    MagneticPatches bad({a, b}, mat);
    ADD_FAILURE() << "overlapping patches accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("patches 0 and 1 overlap"), std::string::npos) << e.what();
  }
  b.origin = {10 * kDx, 0, 0};
  EXPECT_NO_THROW(MagneticPatches({a, b}, mat));
  MagneticStageSettings shield;
  shield.boundary = BoundaryKind::Shield;
  EXPECT_THROW(MagneticPatches({a, b}, mat, shield), InvalidArgument);
  MagneticPatchSettings ps;
  ps.couplingTolerance = 0;
  EXPECT_THROW(MagneticPatches({a, b}, mat, {}, ps), InvalidArgument);
}

TEST(MagneticPatches, ADistantPatchActsThroughAFewMergedExpansions) {
  // Two spheres 1 m apart (200 cells): each sees the other's blocks merged
  // into clusters of an eighth of their distance. That far field against
  // the sum over the other's blocks one by one, at the sphere's centre and
  // at its surface: the merge's truncation, (cluster size / distance)^2
  // (the sphere's blocks span about 4 cm: 1.6e-3 at most).
  const MagneticMaterial mat = paperMaterial();
  const double r = 0.03, d = 1.0;
  const Body a = ballAt({-d / 2, 0, 0}, r, mat.numberDensity, 5), b = ballAt({d / 2, 0, 0}, r, mat.numberDensity, 6);
  std::vector<Vec3d> x = a.x;
  x.insert(x.end(), b.x.begin(), b.x.end());
  const GridSpec box = gridCovering({-d / 2 - 0.1, -0.1, -0.1}, {d / 2 + 0.1, 0.1, 0.1});
  const MaterialPatches found = findMaterialPatches(box, x.data(), x.size(), kPad);
  ASSERT_EQ(found.grids.size(), 2u);
  MagneticPatches patches(found.grids, mat);
  const UniformField src({3e4, 0, 0});
  const MagneticPatchReport rep =
      patches.run({{a.x.data(), a.count.data(), a.x.size()}, {b.x.data(), b.count.data(), b.x.size()}}, src, 0.0);
  ASSERT_TRUE(rep.converged()) << rep.summary();
  double worst = 0;
  for (const Vec3d& at : {Vec3d{-d / 2, 0, 0}, Vec3d{-d / 2 + r, 0, 0}, Vec3d{-d / 2, r, 0}}) {
    Vec3d blockByBlock;
    std::size_t blocks = 0;
    for (const Multipole& m : patches.moments(1)) {
      blockByBlock += m.field(at);
      blocks += m.dipole == Vec3d{} ? 0 : 1;
    }
    ASSERT_GT(blocks, 1u);
    const Vec3d merged = patches.farField(0, at);
    worst = std::max(worst, norm(merged - blockByBlock) / norm(blockByBlock));
  }
  std::printf("far field of a patch 1 m away, merged against block by block: relative %.3g\n", worst);
  EXPECT_LT(worst, 1e-3);
  EXPECT_GT(worst, 0.0);  // merged: not the same sum
}
