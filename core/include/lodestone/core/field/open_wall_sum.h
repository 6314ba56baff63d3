#pragma once
// The open wall's far field at its lattice nodes (open_wall_lattice.h),
// summed for core's solve (magnetostatic_problem.h) and dist/'s alike: the
// blocks' expansions (multipole.h) through a tree. Blocks are merged 2x2x2
// level by level into clusters (moments about the mean of the members'
// centres, mergedMultipole), and a patch of wall nodes takes a cluster as
// one expansion when the cluster's extent s (how far its material can lie
// from its centre, m) over its distance d from the patch is at most theta;
// otherwise it opens the cluster. A truncated expansion's relative error
// grows as (s / d)^2; theta = min(1/4, a block's half diagonal / the
// material's clearance), so that no cluster is taken where its truncation
// exceeds what the nearest wall node already accepts of each block
// (measured: the solve's H and force then differ from the blocks' by less
// than the blocks differ from a larger domain). Each patch's expansions are
// packed once and summed at its nodes four at a time (multipoleSum).
// Clusters and patches are both counted from the two ends of each axis
// towards the grid's mid-plane, as the blocks are (multipole_blocks.h), so
// that the sum, and with it the field of a mirror-symmetric body, is
// mirror-symmetric.
#include <array>
#include <cstddef>
#include <utility>
#include <vector>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/field/multipole.h"
#include "lodestone/core/field/open_wall_lattice.h"

namespace lodestone {
inline namespace field {

class OpenWallSum {
 public:
  /// Sums at the wall's lattice nodes, or at `only` (each on the lattice;
  /// InvalidArgument names the first that is not). `blocks`: one expansion
  /// per block of `blockEdge` cells on `grid` (those with zero moments are
  /// left out); `clearance`: the material's clearance to the wall, in
  /// cells. Throws InvalidArgument for a block edge below 1. Each patch's
  /// expansions are packed, summed at its nodes and dropped: what is kept is
  /// one value a node.
  OpenWallSum(const std::vector<Multipole>& blocks, const GridSpec& grid, int blockEdge, int clearance,
              const OpenWallLattice& lattice, const std::vector<Index3>* only = nullptr);

  /// 4 pi phi (A m) at lattice node (i, j, k): each block's potential, or
  /// that of the largest cluster holding it that the node's patch sees from
  /// at least the cluster's extent / theta. InvalidArgument for a node not
  /// summed.
  double sum(int i, int j, int k) const;
  /// fn(flat node index, 4 pi phi in A m) for every node summed, in index
  /// order.
  template <typename Fn>
  void forEachSum(const Fn& fn) const {
    for (const auto& s : sums_) fn(s.first, s.second);
  }

  /// The acceptance ratio (dimensionless, in (0, 1/4]).
  double theta() const { return theta_; }
  /// Expansions summed per node on average (the blocks' count without the
  /// tree), and the patches of nodes.
  double meanTerms() const { return meanTerms_; }
  std::size_t patchCount() const { return patchCount_; }

  /// Lattice spacings per patch edge: a patch holds up to 4 x 4 of a face's
  /// lattice nodes, and spans at most 1.6 clearances (the spacing is at most
  /// 0.4 of it): wider patches see fewer clusters from far enough to take
  /// them whole, narrower ones pack their expansions for fewer nodes.
  static constexpr int kPatchLattice = 4;

 private:
  using Key = std::array<long, 3>;
  Key patchKey(int i, int j, int k) const;

  GridSpec grid_;
  int patchNodes_ = 0;  // grid nodes per patch edge
  double theta_ = 0.25;
  double meanTerms_ = 0;
  std::size_t patchCount_ = 0;
  std::vector<std::pair<std::size_t, double>> sums_;  // (flat node index, 4 pi phi in A m), ascending
};

/// Expansions merged into one about the mean of their centres c:
/// m = sum m_b, N_ij = sum (N_b,ij + m_b,i (c_b - c)_j).
Multipole mergedMultipole(const Multipole* const* members, std::size_t count);

}  // namespace field
}  // namespace lodestone
