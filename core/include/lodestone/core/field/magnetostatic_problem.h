#pragma once
// The discrete magnetostatic problem of one field solve (docs/physics.md):
// unknown scalar potential phi on the grid nodes, trilinear elements with
// 2x2x2 Gauss points, H = H_ext - grad(phi), and the convex energy
//   E(phi) = sum_cells sum_q w_q [ |grad phi|^2 / 2 + W(n_q, H_ext,q - grad phi_q) ]
// whose gradient is the residual F and whose Hessian is the SPD Jacobian
// J = G^T (I + dM/dH) G. H_ext is not differentiated (it is divergence-free),
// so an empty box keeps H = H_ext exactly.
//
// Boundary semantics (BoundaryKind):
//  - Open: phi on the outer layer of nodes is the free-space potential of
//    the current magnetization (a far-field condition), summed over cubic
//    blocks of cells (edge 8 cells, up to 32 when the material is far from
//    the wall), each as a dipole + quadrupole about its own centroid; far
//    from a patch of wall nodes, blocks merged into clusters stand in for
//    their members (open_wall_sum.h). Blocks, clusters, patches and the wall
//    lattice on which the sum is evaluated are counted from both ends of
//    each axis, so a mirror-symmetric body in a symmetric field gets no net
//    force from the wall on any grid size. Interior nodes are unknowns.
//  - Shield: the paper's wall, grad(phi).n = M.n (natural condition); every
//    node is an unknown and phi is defined up to a constant (kept at mean 0).
//
// All loops are TBB-parallel and deterministic: scatters from cells to nodes
// run in 8 colour passes (cell parity), so every node sums its contributions
// in a fixed order, and reductions use deterministicSum.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "lodestone/core/field/boundary_kind.h"
#include "lodestone/core/base/grid.h"
#include "lodestone/core/field/hull_stencil.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/base/mat3.h"
#include "lodestone/core/field/multipole.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace field {

/// Fills H[0..count) (A/m) with the applied field at x[0..count) (m).
/// Called from several threads at once on disjoint ranges.
using AppliedFieldFunction = std::function<void(const Vec3d* x, std::size_t count, Vec3d* H)>;

class MagnetostaticProblem {
 public:
  MagnetostaticProblem(const GridSpec& grid, const MagnetizationLaw<double>& law, BoundaryKind boundary);

  /// Finds the material cells (any corner with n > 0), interpolates n (1/m^3)
  /// to their Gauss points and evaluates the applied field there.
  /// `sameAppliedField`: the caller knows that appliedField is the field of
  /// the previous call (the sources and their poses unchanged); cells that
  /// were material then keep their Gauss points' values, and only the new
  /// cells are evaluated (the values are those a fresh evaluation gives, bit
  /// for bit, as long as the function evaluates each point on its own).
  /// Throws InvalidArgument on a negative or non-finite density.
  void setMaterial(GridView<const double> n, const AppliedFieldFunction& appliedField,
                   bool sameAppliedField = false);
  /// Material cells whose Gauss points' applied field the last setMaterial
  /// evaluated (the others kept their values).
  std::size_t appliedFieldCellsEvaluated() const { return cellsEvaluated_; }

  const GridSpec& grid() const { return grid_; }
  BoundaryKind boundary() const { return boundary_; }
  const MagnetizationLaw<double>& law() const { return law_; }
  std::size_t nodeCount() const { return grid_.nodeCount(); }
  std::size_t materialCellCount() const { return cellBase_.size(); }
  /// Nodes that are unknowns (interior nodes for Open, all for Shield).
  std::size_t freeNodeCount() const;
  bool isFree(int i, int j, int k) const {
    return boundary_ == BoundaryKind::Shield || !grid_.isBoundaryNode(i, j, k);
  }
  /// Smallest distance, in cells, between a material cell and the outer wall
  /// (large when there is no material).
  int materialWallClearance() const { return wallClearance_; }
  /// n-weighted centroid of the material, m.
  const Vec3d& materialCentroid() const { return centroid_; }
  /// Integral of n over the domain (micro-particle count).
  double totalCount() const { return totalCount_; }

  struct Evaluation {
    double materialEnergy = 0;   ///< sum_q w_q W_q, A^2 m (mu0 * this is J)
    double materialEnergyAbs = 0;///< sum_q w_q |W_q|, for round-off estimates
    std::vector<Multipole> multipoles;  ///< of the current magnetization, one per block
    bool finite = true;          ///< false when any M or dM/dH was not finite
  };
  /// Evaluates M and W at every material Gauss point for potential phi and
  /// writes the residual F = dE/dphi (A m) on free nodes (0 on fixed nodes).
  /// With `jacobian`, also rebuilds the element matrices and their assembled
  /// rows (materialStencil()), which applyJacobian uses.
  /// `vacuumPart`, when given, is applyVacuum(phi) already computed by the
  /// caller (the Newton loop keeps it up to date); it is copied into F
  /// instead of applying the stencil again (vacuumPart == F: F holds it).
  Evaluation evaluate(const double* phi, double* F, bool jacobian = true, const double* vacuumPart = nullptr);

  /// Residual of the material part alone at phi = 0 (the reference scale of
  /// relative residuals): F0 = -G^T w M(H_ext). Does not change the stored Jacobian.
  void residualAtZero(double* F0) const;

  /// out = K v on free nodes (the vacuum Laplacian stencil, m), 0 on fixed
  /// nodes. Values of v on fixed nodes enter the free rows next to them.
  void applyVacuum(const double* v, double* out) const;
  /// out = J v with the Jacobian blocks of the last evaluate().
  void applyJacobian(const double* v, double* out) const;
  /// out = J v as applyJacobian, in one pass over the rows that also
  /// returns v . J v (deterministic: per-row sums added in row order).
  /// Uses storage kept in the problem: not for concurrent calls.
  double applyJacobianDot(const double* v, double* out) const;
  /// out += K v_w on the free rows next to the wall, where v_w is v on the
  /// fixed (wall) nodes and 0 elsewhere: what a change of the wall values
  /// does to applyVacuum, at the cost of the wall layer only. Nothing for
  /// Shield (no fixed nodes).
  void addWallCoupling(const double* v, double* out) const;
  /// Flat indices of the fixed (wall) nodes, in index order (empty for Shield).
  std::vector<std::size_t> fixedNodes() const;
  /// diag(J) on free nodes (1 on fixed nodes).
  void jacobianDiagonal(double* out) const;

  /// sum_q w_q W at phi + lambda * delta, and sum of |w_q W| in *absSum.
  double materialEnergyAlong(const double* phi, const double* delta, double lambda, double* absSum) const;

  /// Base node (flat index) of material cell `slot` (0 <= slot < materialCellCount()).
  std::size_t materialCellBase(std::size_t slot) const { return cellBase_[slot]; }
  /// Mean dM/dH over the Gauss points of material cell `slot` at the last
  /// evaluate(..., true): the coefficient coarse multigrid levels use.
  const SymMat3d& materialCellTensor(std::size_t slot) const { return cellTensor_[slot]; }
  /// Values in the packed upper triangle of a symmetric 8x8 element matrix.
  static constexpr int kPacked = 36;
  /// The material element matrices of the last evaluate(..., true)
  /// assembled into 27-point rows at the nodes they touch (m): applyJacobian
  /// adds their product to the vacuum stencil's, and the multigrid's level 0
  /// copies them.
  const HullStencil<double>& materialStencil() const { return stencil_; }
  /// Material cells are grouped by colour (cell parity): slots
  /// [materialColourStart()[c], materialColourStart()[c + 1]) have colour c.
  const std::size_t* materialColourStart() const { return colourStart_; }

  /// Open boundary: writes the blocks' summed far-field potential
  /// (OpenWallSum) into the fixed nodes of phi.
  void applyOpenBoundary(const std::vector<Multipole>& multipoles, double* phi) const;

  /// Block multipoles of the first-order change of M when phi changes by
  /// dphi (one value per node), at the last evaluate(..., true):
  /// dM = (dM/dH) dH with dH = -grad dphi at each Gauss point and dM/dH the
  /// cell's mean tensor (materialCellTensor). The same blocks and centres
  /// as Evaluation::multipoles; applyOpenBoundary of the result predicts how
  /// the wall values will move.
  std::vector<Multipole> linearizedMultipoles(const double* dphi) const;

  /// Smallest edge of the multipole blocks, in cells.
  static constexpr int kMultipoleBlock = 8;
  /// Edge of the multipole blocks of the current material, in cells.
  int multipoleBlockEdge() const { return blockEdge_; }
  /// Number of multipole blocks of the current material.
  std::size_t multipoleBlockCount() const { return blockCentre_.size(); }

  /// Shield boundary: subtracts the mean over all nodes (the null space).
  void removeMean(double* v) const;

  /// Zeroes the fixed (boundary) nodes for Open; nothing for Shield.
  void zeroFixed(double* v) const;

 private:
  // Per-cell partial sums of evaluate(): the energies are reduced over all
  // cells, the multipole moments per block, both in a fixed order. Kept
  // between calls (no allocation in the Newton loop).
  struct CellSums {
    double energy = 0, energyAbs = 0;
    Multipole multipole;
    bool finite = true;
  };
  std::vector<CellSums> sums_;
  mutable std::vector<double> rowSums_;  // applyJacobianDot's per-row partial sums

  template <typename CellFn>
  void scatterCells(double* out, const CellFn& cellFn) const;
  /// blockCells_, blockStart_ and cellBlock_ from cellBase_ and blockEdge_.
  void sortCellsIntoBlocks();
  void gatherCorners(std::size_t base, const double* v, double c[8]) const;
  Vec3d cellOrigin(std::size_t base) const;

  GridSpec grid_;
  MagnetizationLaw<double> law_;
  BoundaryKind boundary_;
  std::size_t cornerOffset_[8];
  // Material cells, grouped by colour (cell parity); colourStart_[c] .. colourStart_[c+1].
  std::vector<std::size_t> cellBase_;  // base node index of each material cell
  std::vector<std::size_t> previousCellBase_;  // setMaterial(): the previous call's cells (storage kept)
  std::size_t colourStart_[9] = {};
  std::size_t cellsEvaluated_ = 0;     // cells whose applied field the last setMaterial evaluated
  bool haveAppliedField_ = false;      // hext_ holds the values of cellBase_'s cells
  std::vector<double> nq_;             // density at Gauss points, 8 per cell, 1/m^3
  std::vector<Vec3d> hext_;            // applied field at Gauss points, A/m
  std::vector<Vec3d> hextSpare_;       // where setMaterial moves kept values when the cells change
  // Material element matrices sum_q w dN_q^T dM/dH_q dN_q / dx^2 (packed upper
  // triangle of the symmetric 8x8, kPacked values per cell), rebuilt by evaluate().
  std::vector<double> elem_;
  std::vector<SymMat3d> cellTensor_;
  HullStencil<double> stencil_;        // elem_ assembled per node, rebuilt by evaluate(..., true)
  int wallClearance_ = 1 << 30;
  Vec3d centroid_;
  int blockEdge_ = kMultipoleBlock;
  std::vector<std::size_t> blockStart_;  // blocks: blockCells_[blockStart_[b] .. blockStart_[b+1])
  std::vector<std::size_t> blockCells_;  // material cell slots sorted by block
  std::vector<Vec3d> blockCentre_;       // n-weighted centroid of each block, m
  std::vector<std::uint32_t> cellBlock_; // block of each material cell slot
  bool haveBlocks_ = false;              // the blocks above belong to cellBase_ (a completed setMaterial)
  std::vector<Vec3d> cellFromCentre_;    // each cell slot's origin minus its block's centre, m
  double totalCount_ = 0;
};

}  // namespace field
}  // namespace lodestone
