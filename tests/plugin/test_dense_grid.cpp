// The sparse MPM grid (the runs of nodes the particles reach on each x-row,
// mpm/grid.h) against the grid held whole (MpmSettings::denseGrid): 100
// substeps of every example scene, with all its stages (magnetism, surface
// tension, colliders, emitters, rigid bodies), give the same particles bit
// for bit. Only storage differs: a run that missed a node a stencil reaches,
// or a node of an earlier run left unzeroed, changes them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "lodestone/plugin/scene.h"

using namespace lodestone;
using namespace lodestone::plugin;

namespace {

template <typename T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

/// The nodes of the grid's runs (MpmGrid::activeRun) over its active box.
double heldNodes(const MpmGrid& grid) {
  double nodes = 0;
  const Index3 lo = grid.activeLo(), hi = grid.activeHi();
  for (int k = lo.k; k < hi.k; ++k)
    for (int j = lo.j; j < hi.j; ++j) {
      int first = 0, end = 0;
      grid.activeRun(j, k, first, end);
      nodes += double(std::max(0, end - first));
    }
  return nodes;
}

}  // namespace

TEST(DenseGrid, EveryExampleSceneGivesTheSameParticlesAfter100Substeps) {
  constexpr int kSubsteps = 100;
  int scenes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(LODESTONE_SCENES_DIR)) {
    if (entry.path().extension() != ".json") continue;
    ++scenes;
    SCOPED_TRACE(entry.path().string());
    Scene scene = loadScene(entry.path().string());
    const auto sparse = buildSolver(scene);
    scene.settings.denseGrid = true;
    const auto dense = buildSolver(scene);
    for (int s = 0; s < kSubsteps; ++s) {
      const double dt = sparse->suggestedDt();
      ASSERT_EQ(dt, dense->suggestedDt()) << "substep " << s;
      sparse->step(dt);
      dense->step(dt);
    }
    const MpmParticles &a = sparse->particles(), &b = dense->particles();
    const double held = heldNodes(sparse->grid()), whole = heldNodes(dense->grid());
    std::printf("%s: %zu particles after %d substeps (%.3g s); the sparse grid held %.0f of %.0f nodes\n",
                entry.path().stem().c_str(), a.size(), kSubsteps, sparse->time(), held, whole);
    EXPECT_EQ(whole, double(scene.settings.grid.nodeCount()));
    EXPECT_LT(held, whole);
    ASSERT_GT(a.size(), 0u);
    EXPECT_TRUE(sameBits(a.id, b.id));
    EXPECT_TRUE(sameBits(a.x, b.x));
    EXPECT_TRUE(sameBits(a.v, b.v));
    EXPECT_TRUE(sameBits(a.C, b.C));
    EXPECT_TRUE(sameBits(a.F, b.F));
    EXPECT_TRUE(sameBits(a.J, b.J));
  }
  EXPECT_GE(scenes, 10);
}
