#pragma once
// Device-resident nonlinear field solve: core's Newton solver
// (lodestone/core/field/newton_solver.h) on the CUDA backend, or on its serial
// host reference. The same discrete problem (trilinear elements, 2x2x2 Gauss
// points, energy sum_q w_q [|grad phi|^2/2 + W(n_q, H_ext,q - grad phi_q)]),
// the same Newton iteration, settings (lodestone::FieldSolveSettings) and
// report (lodestone::FieldSolveReport) as core's solveField, with PCG
// preconditioned by Jacobi or by the geometric multigrid V-cycle, every
// operator applied matrix-free on the device. Only scalars (norms, energies)
// cross the bus inside the solve, and the open wall's far field, which the
// host computes.
//
// Differences from core's backend: the V-cycle's levels are stored in double
// precision (MultigridSettings::singlePrecision is ignored), and sums are
// formed in another order (results agree to round-off, not bitwise).
//
// Boundaries:
//  - Shield (the Neumann wall): fully supported.
//  - Open: the wall nodes are Dirichlet nodes. By default they hold the
//    values that `phi` carries on entry to solve() for the whole solve; with
//    setWallUpdate() the host recomputes them from the magnetization (as
//    core does from block multipoles), and with the optional linearized
//    update the wall moves with each Newton step (FieldSolveSettings::
//    predictWall), as in core.
//
// Usage (no TBB, no OpenVDB, raw arrays; x fastest, one value per node):
//
//   lodestone::gpu::FieldSolver solver(grid, law, lodestone::BoundaryKind::Shield,
//                                      lodestone::gpu::Backend::Auto);
//   solver.setMaterial(n, [&](const Vec3d* x, std::size_t count, Vec3d* H) { ... });  // H_ext at x, A/m
//   std::vector<double> phi(grid.nodeCount(), 0.0);           // warm start, A
//   lodestone::FieldSolveReport r = solver.solve(phi.data());
//   if (!r.converged()) std::cerr << r.message << "\n";
//
// Then lodestone::gpu::magneticForce() (magnetic_force.h) gives H, B and the
// nodal force from phi.
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <utility>

#include "lodestone/core/field/boundary_kind.h"
#include "lodestone/core/base/grid.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/core/field/solve_report.h"
#include "lodestone/core/field/solve_settings.h"
#include "lodestone/gpu/backend.h"

namespace lodestone {
namespace gpu {

/// Fills H[0..count) (A/m) with the applied field at x[0..count) (m).
using AppliedField = std::function<void(const Vec3d* x, std::size_t count, Vec3d* H)>;

/// Open wall, far field on the host. `values`: called with a potential
/// `phi` (A, all nodes) whenever the solver moves the wall to the far field
/// of the magnetization at phi; writes the wall values into `wall` (all
/// nodes, initialised to phi; only the wall nodes are read back). A host with
/// the core library computes them as core's backend does:
/// MagnetostaticProblem::evaluate(phi, F, true) (block multipoles of M), then
/// applyOpenBoundary. `move` (optional): the wall move of a Newton step
/// `d` (A, all nodes), linearized at the potential last given to `values`,
/// into the wall nodes of `wall` (initialised to 0); with core,
/// applyOpenBoundary(linearizedMultipoles(d)).
using WallUpdate = std::function<void(const double* phi, double* wall)>;

class FieldSolver {
 public:
  /// Throws InvalidArgument on a bad grid, Error when `backend` is Cuda and
  /// no device is usable (Auto falls back to the CPU; see backendMessage()).
  FieldSolver(const GridSpec& grid, const MagnetizationLaw<double>& law, BoundaryKind boundary,
              Backend backend = Backend::Auto);
  ~FieldSolver();
  FieldSolver(const FieldSolver&) = delete;
  FieldSolver& operator=(const FieldSolver&) = delete;

  /// The backend in use (Cpu or Cuda) and why Auto chose the CPU (empty otherwise).
  Backend backend() const { return backend_; }
  const std::string& backendMessage() const { return backendMessage_; }
  const GridSpec& grid() const { return grid_; }

  /// n: micro-particle density (1/m^3), one per node. Finds the material
  /// cells, interpolates n to their Gauss points, evaluates H_ext there on the
  /// host and uploads both. Throws InvalidArgument on a negative or
  /// non-finite density or a non-finite applied field.
  void setMaterial(const double* n, const AppliedField& appliedField);
  std::size_t materialCellCount() const;

  /// Open wall only: the far field on the host (see WallUpdate; each call
  /// downloads and uploads one vector). Without it the wall values of phi on
  /// entry are kept; without `move` the wall follows M one iteration late.
  void setWallUpdate(WallUpdate values, WallUpdate move = {}) {
    wallValues_ = std::move(values);
    wallMove_ = std::move(move);
  }

  /// Solves in place: phi (A, one per node) holds the warm start (and, for
  /// Open, the wall values) on entry and the solution on return. Never
  /// leaves non-finite values in phi.
  FieldSolveReport solve(double* phi, const FieldSolveSettings& settings = {});

 private:
  GridSpec grid_;
  MagnetizationLaw<double> law_;
  BoundaryKind boundary_;
  Backend backend_;
  std::string backendMessage_;
  WallUpdate wallValues_, wallMove_;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gpu
}  // namespace lodestone
