#pragma once
// The operations the Newton-PCG-multigrid driver (newton_driver.h) needs from
// a backend. The driver is written once over this interface; the host
// reference backend runs it with serial loops over host memory, the CUDA
// backend with kernels over device memory. Vectors are plain pointers into the
// backend's memory space; the driver never dereferences them.
#include <cstddef>
#include <memory>
#include <vector>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/gpu/field_solver.h"

namespace lodestone {
namespace gpu {
namespace detail {

/// The material of one field solve, prepared on the host and shared by the
/// backends so that both see bitwise the same inputs.
struct FieldProblemData {
  GridSpec grid;
  MagnetizationLaw<double> law;
  bool shield = true;                 ///< Shield (all nodes free) or Open (wall nodes fixed)
  std::vector<std::size_t> cellBase;  ///< base node of each material cell, ascending
  std::vector<double> nq;             ///< density at the Gauss points, 8 per cell, 1/m^3
  std::vector<Vec3d> hext;            ///< applied field at the Gauss points, 8 per cell, A/m
};

/// Finds the material cells of density n (1/m^3, one per node), interpolates
/// n to their Gauss points and evaluates the applied field there. Throws
/// InvalidArgument on a negative or non-finite density or applied field.
FieldProblemData prepareProblem(const GridSpec& grid, const MagnetizationLaw<double>& law, bool shield, const double* n,
                                const AppliedField& appliedField);

struct Evaluation {
  double energy = 0;     ///< sum_q w_q W_q, A^2 m
  double energyAbs = 0;  ///< sum_q w_q |W_q|
  bool finite = true;
};

constexpr int kWorkSlots = 40;

class FieldBackend {
 public:
  virtual ~FieldBackend() = default;

  /// Uploads the material; invalidates the preconditioner.
  virtual void setProblem(const FieldProblemData& data) = 0;

  // Memory.
  virtual double* allocate(std::size_t n) = 0;  ///< owned by the backend until it is destroyed
  virtual void upload(const double* host, std::size_t n, double* dst) = 0;
  virtual void download(const double* src, std::size_t n, double* host) = 0;

  // Vector operations on n entries (dot and sum are deterministic).
  virtual void fill(std::size_t n, double value, double* x) = 0;
  virtual void copy(std::size_t n, const double* x, double* y) = 0;
  /// out = a x + b y (out may alias x or y).
  virtual void axpby(std::size_t n, double a, const double* x, double b, const double* y, double* out) = 0;
  virtual double dot(std::size_t n, const double* x, const double* y) = 0;
  /// x = w d .* b when r == nullptr, else x += w d .* (b - r).
  virtual void jacobi(std::size_t n, double w, const double* d, const double* b, const double* r, double* x) = 0;
  /// Subtracts the mean (Shield's null space).
  virtual void removeMean(std::size_t n, double* v) = 0;

  // The fine problem (level 0).
  virtual std::size_t nodeCount() const = 0;
  virtual std::size_t materialCellCount() const = 0;
  virtual bool shield() const = 0;
  virtual const MagnetizationLaw<double>& law() const = 0;
  virtual Evaluation evaluate(const double* phi, double* F, bool jacobian) = 0;
  virtual void residualAtZero(double* F0) = 0;
  virtual void applyVacuum(const double* v, double* out) = 0;
  virtual double energyAlong(const double* phi, const double* delta, double lambda, double* absSum) = 0;

  // Preconditioner levels (level 0 is the fine Jacobian).
  /// Rebuilds the inverse diagonals (and, with multigrid, the coarse levels
  /// down to an axis of coarsestNodes nodes or fewer) from the last
  /// evaluate(..., true).
  virtual void buildPreconditioner(bool multigrid, int coarsestNodes) = 0;
  virtual int levelCount() const = 0;
  virtual std::size_t levelNodes(int level) const = 0;
  virtual void applyLevel(int level, const double* v, double* out) = 0;
  virtual void zeroFixed(int level, double* v) = 0;
  /// Jacobi: 1/diag(J) (1 on fixed rows); multigrid levels: 1/diag, 0 on fixed rows.
  virtual const double* inverseDiagonal(int level, bool jacobiPreconditioner) = 0;
  virtual void restrictTo(int fineLevel, const double* fine, double* coarse) = 0;
  virtual void prolong(int fineLevel, const double* coarse, double* fine) = 0;
  /// Solves A_level x = b on the coarsest level when the backend has a
  /// faster way than the driver's CG through these operations (same
  /// algorithm: diagonal-preconditioned CG from x = 0 to relative residual
  /// 1e-10, at most 10 n iterations, mean removed for Shield); returns false
  /// to let the driver run it.
  virtual bool solveCoarsest(int level, const double* b, double* x) {
    (void)level;
    (void)b;
    (void)x;
    return false;
  }
  /// A persistent work vector of a level (slot 0..kWorkSlots-1), allocated on first use.
  virtual double* work(int level, int slot) = 0;

  virtual const char* name() const = 0;
};

std::unique_ptr<FieldBackend> makeHostFieldBackend();
/// Throws lodestone::Error when the CUDA backend is not built or no device is present.
std::unique_ptr<FieldBackend> makeDeviceFieldBackend();

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
