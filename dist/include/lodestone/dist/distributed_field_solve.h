#pragma once
// The field solve of one scene across MPI ranks, on PETSc (docs/distributed.md).
//
// The node grid of the field solve is a DMDA (3D, box stencil of width 1,
// one unknown per node) split into one box of nodes per rank. Each rank owns
// the cells whose base node (lowest corner) it owns, evaluates the material
// at their Gauss points with core's element kernels (q1_element.h,
// langevin_batch.h, element_build.h) and adds their element residuals and
// matrices into the ghosted nodes they touch (DMLocalToGlobal with
// ADD_VALUES; MatSetValuesStencil with ADD_VALUES). The nonlinear problem is
// the one of MagnetostaticProblem (magnetostatic_problem.h):
//   F(phi) = K phi - G^T w M(H_ext - grad phi),  J = G^T (I + dM/dH) G,
// solved by SNES (Newton, backtracking line search on ||F||, Eisenstat-Walker
// inner tolerances) with KSPCG preconditioned by PCMG on the DMDA hierarchy
// (Galerkin coarse operators), PCGAMG or hypre BoomerAMG.
//
// Fixed nodes hold target values g and carry the rows c (phi - g); every
// other row sees g, not phi, on them, so the Jacobian stays symmetric:
//  - Open: the wall nodes; g is the far field of the current magnetization,
//    from the block multipoles of core (multipole_blocks.h) whose moment sums
//    are reduced over the ranks (MPI_Allreduce) before each rank sums them on
//    its own wall nodes. The wall follows M within the Newton iteration, as
//    core's lagging wall does.
//  - Shield: node (0, 0, 0) with g = 0, which removes the constant null space
//    (the dropped equation is implied by the others: the rows of F sum to 0).
//    The potential returned has mean 0, as core's.
#include <memory>
#include <string>
#include <vector>

#include <mpi.h>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/field/boundary_kind.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/field/magnetostatic_problem.h"

namespace lodestone {
inline namespace dist {

/// The preconditioner of the distributed CG solves.
enum class DistributedPreconditioner : int {
  /// PCMG on the DMDA hierarchy, Galerkin coarse operators; PCGAMG on a
  /// grid whose cell counts do not halve at least twice on every axis
  GeometricMultigrid = 0,
  Gamg = 1,                ///< PETSc's smoothed-aggregation algebraic multigrid
  Hypre = 2                ///< hypre BoomerAMG (when PETSc was built with hypre)
};
const char* toString(DistributedPreconditioner kind);
/// Parses "mg", "gamg" or "hypre"; throws InvalidArgument naming the value.
DistributedPreconditioner parseDistributedPreconditioner(const std::string& name);

struct DistributedSolveSettings {
  double tolerance = 1e-8;  ///< stop at ||F|| <= tolerance * ||F(0)||
  int maxNewtonIterations = 40;
  DistributedPreconditioner preconditioner = DistributedPreconditioner::GeometricMultigrid;
  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
};

struct DistributedSolveReport {
  bool converged = false;
  bool trivial = false;            ///< nothing magnetized: phi = 0
  int ranks = 1;
  int newtonIterations = 0;
  int linearIterations = 0;        ///< CG iterations over all Newton steps
  double relativeResidual = 0;     ///< ||F|| / ||F(0)|| at the end
  double seconds = 0;              ///< wall time of solve(), s
  double setupSeconds = 0;         ///< of setMaterial(), s
  std::string reason;              ///< SNES's converged reason, as text
  std::string summary() const;
};

class DistributedFieldSolve {
 public:
  /// Collective over `comm`; PETSc must be initialized (PetscSession).
  DistributedFieldSolve(MPI_Comm comm, const GridSpec& grid, const MagnetizationLaw<double>& law,
                        BoundaryKind boundary, const DistributedSolveSettings& settings = {});
  ~DistributedFieldSolve();
  DistributedFieldSolve(const DistributedFieldSolve&) = delete;
  DistributedFieldSolve& operator=(const DistributedFieldSolve&) = delete;

  /// Collective. n (1/m^3) on the solver grid; each rank reads only the nodes
  /// of its own cells (the array may be replicated or hold only those).
  /// Throws InvalidArgument on a negative or non-finite density.
  void setMaterial(GridView<const double> n, const AppliedFieldFunction& appliedField);

  /// Collective. Solves from phi = 0.
  DistributedSolveReport solve();

  /// Collective. phi (A) at every node in flat index order on rank `root`;
  /// empty on the other ranks.
  std::vector<double> gatherPotential(int root = 0) const;

  /// This rank's nodes: [lo, hi) per axis.
  Index3 ownedLo() const;
  Index3 ownedHi() const;
  int ranks() const;
  int rank() const;

  /// The PETSc components of the solve as text (SNES, KSP, PC types, levels).
  std::string describe() const;

  struct Impl;  ///< the PETSc objects and this rank's cells (opaque)

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace dist
}  // namespace lodestone
