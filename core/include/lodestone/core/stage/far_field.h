#pragma once
// The far field of other patches of material over one patch's grid
// (stage/magnetic_patches.h): their block expansions summed, and sampled on
// a coarse lattice where that field is smooth enough to interpolate.
#include <vector>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/core/field/multipole.h"

namespace lodestone {
inline namespace stage {

/// The field H (A/m) of `blocks` at x (m): the sum of their expansions.
Vec3d farFieldOf(const std::vector<Multipole>& blocks, const Vec3d& x);

/// Distance (m) from grid g's box to the box of the centres of `blocks`
/// (infinite when there are none): at most the distance to the nearest.
double distanceToBlocks(const GridSpec& g, const std::vector<Multipole>& blocks);

/// The far field of `blocks` over grid g's box: at the nodes of a lattice
/// of spacing h whole cells covering the box and one cell beyond,
/// interpolated trilinearly, where the nearest block lies d >= 16 h away
/// (h >= 2 cells); summed exactly elsewhere and when blocks are nearer. A
/// dipole's field has second derivatives of at most 12 |H| / d^2, so the
/// interpolation is within 1.5 (h / d)^2 <= 0.6% of the far field (itself a
/// small part of the applied field), and a patch 60 cells from another sums
/// 27 times fewer expansions.
class SampledFarField {
 public:
  SampledFarField(std::vector<Multipole> blocks, const GridSpec& g);
  /// H (A/m) at x (m).
  Vec3d at(const Vec3d& x) const;
  /// The lattice's spacing, m (0: summed exactly everywhere).
  double spacing() const { return step_; }

 private:
  std::size_t index(int i, int j, int k) const;
  std::vector<Multipole> blocks_;
  std::vector<Vec3d> samples_;
  Vec3d lo_;
  double step_ = 0;
  int n_[3] = {0, 0, 0};
};

}  // namespace stage
}  // namespace lodestone
