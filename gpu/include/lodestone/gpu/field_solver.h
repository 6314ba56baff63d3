#pragma once
// Device-resident nonlinear field solve (the CUDA counterpart of
// core/field_solver.h): the same discrete problem (trilinear elements, 2x2x2
// Gauss points, energy sum_q w_q [|grad phi|^2/2 + W(n_q, H_ext,q - grad phi_q)]),
// the same inexact Newton with Eisenstat-Walker forcing and the same
// energy/residual line search, and PCG preconditioned by Jacobi or by the same
// geometric multigrid V-cycle, with every operator applied matrix-free on the
// device. Only scalars (norms, energies) cross the bus inside the solve.
//
// Boundaries:
//  - Shield (the Neumann wall): fully supported, identical to the CPU.
//  - Open: the wall nodes are Dirichlet nodes. By default they hold the
//    values that `phi` carries on entry to solve() for the whole solve; with
//    setWallUpdate() the host recomputes them at the start of every Newton
//    iteration (as the CPU solver does from block multipoles), and the device
//    receives them with one upload per iteration.
//
// Usage (no TBB, no OpenVDB, raw arrays; x fastest, one value per node):
//
//   lodestone::gpu::FieldSolver solver(grid, law, lodestone::BoundaryKind::Shield,
//                                      lodestone::gpu::Backend::Auto);
//   solver.setMaterial(n, [&](const Vec3d* x, std::size_t count, Vec3d* H) { ... });  // H_ext at x, A/m
//   std::vector<double> phi(grid.nodeCount(), 0.0);           // warm start, A
//   lodestone::gpu::FieldSolveReport r = solver.solve(phi.data());
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
#include "lodestone/gpu/backend.h"

namespace lodestone {
namespace gpu {

enum class Preconditioner : int { Jacobi = 0, Multigrid = 1 };

/// The settings of core's FieldSolveSettings, with the same defaults.
struct FieldSolveSettings {
  double tolerance = 1e-8;  ///< stop at ||F|| <= tolerance ||F_ref|| (F_ref: residual at phi = 0)
  int maxNewtonIterations = 40;
  int maxCgIterations = 5000;  ///< per Newton step
  double forcingMax = 0.1;     ///< largest inner relative tolerance (Eisenstat-Walker)
  double forcingGamma = 0.9;
  double forcingAlpha = 2.0;
  int maxLineSearchCuts = 30;
  double armijo = 1e-4;
  Preconditioner preconditioner = Preconditioner::Multigrid;
  int smoothing = 2;          ///< damped-Jacobi sweeps before and after the coarse correction
  double jacobiWeight = 0.7;  ///< smoother damping in (0, 1]
  int coarsestNodes = 5;      ///< stop coarsening when an axis has this many nodes or fewer

  /// Throws lodestone::InvalidArgument naming the first bad value.
  void validate() const;
};

/// Same codes as core's SolveStatus.
enum class SolveStatus : int {
  Converged = 0,
  Trivial = 1,
  IterationCap = 2,
  LineSearchFailed = 3,
  LinearSolverFailed = 4,
  NonFinite = 5
};
const char* toString(SolveStatus status);

struct FieldSolveReport {
  SolveStatus status = SolveStatus::Trivial;
  int newtonIterations = 0;
  int cgIterations = 0;  ///< total over the Newton steps
  int lineSearchCuts = 0;
  double relativeResidual = 0;   ///< final ||F|| / ||F_ref||
  double referenceResidual = 0;  ///< ||F_ref||, A m
  double materialEnergy = 0;     ///< sum w W at the solution, A^2 m
  double seconds = 0;            ///< wall time of solve(), including transfers of phi
  std::size_t materialCells = 0;
  int multigridLevels = 0;
  std::string backend;  ///< "cpu" or "cuda"
  std::string message;

  bool converged() const { return status == SolveStatus::Converged || status == SolveStatus::Trivial; }
};

/// Fills H[0..count) (A/m) with the applied field at x[0..count) (m).
using AppliedField = std::function<void(const Vec3d* x, std::size_t count, Vec3d* H)>;

/// Open wall, far-field update: called on the host at the start of every
/// Newton iteration with the current potential `phi` (A, all nodes); writes
/// the new wall values into `wall` (all nodes, initialised to phi; only the
/// wall nodes are read back). A host with the core library computes them as
/// core's solver does: MagnetostaticProblem::evaluate (block multipoles of the
/// magnetization) then applyOpenBoundary.
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

  /// Open wall only: refresh the wall values at every Newton iteration
  /// (one download and upload of phi and one extra residual evaluation per
  /// iteration). Without it the wall values of phi on entry are kept.
  void setWallUpdate(WallUpdate update) { wallUpdate_ = std::move(update); }

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
  WallUpdate wallUpdate_;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gpu
}  // namespace lodestone
