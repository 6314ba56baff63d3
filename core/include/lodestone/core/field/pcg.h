#pragma once
// Preconditioned conjugate gradients for the SPD Newton systems of the field
// solve, and the preconditioners it can use. Vectors are plain arrays of one
// value per grid node; dot products are deterministic (parallel.h).
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace lodestone {
inline namespace field {

class MagnetostaticProblem;

/// z = P^{-1} r for an SPD approximation P of the Jacobian.
class Preconditioner {
 public:
  virtual ~Preconditioner() = default;
  /// Called after every MagnetostaticProblem::evaluate (the Jacobian changed).
  virtual void update(const MagnetostaticProblem& problem) = 0;
  virtual void apply(const double* r, double* z) const = 0;
  /// apply() and r . z over the n values, deterministic; preconditioners
  /// that can form the sum while they write z override it.
  virtual double applyDot(std::size_t n, const double* r, double* z) const;
  virtual std::string name() const = 0;
};

/// Diagonal (Jacobi) scaling by diag(J).
class JacobiPreconditioner final : public Preconditioner {
 public:
  void update(const MagnetostaticProblem& problem) override;
  void apply(const double* r, double* z) const override;
  std::string name() const override { return "jacobi"; }

 private:
  std::vector<double> inverseDiagonal_;
};

struct PcgResult {
  int iterations = 0;
  double relativeResidual = 0;  ///< ||b - A x|| / ||b|| (recursive residual)
  bool converged = false;
  bool breakdown = false;       ///< p^T A p <= 0 or non-finite values
};

/// Scratch vectors of solvePcg, kept by callers that solve repeatedly.
struct PcgWorkspace {
  std::vector<double> r, z, p, Ap;
};

/// Solves A x = b from x = 0 until ||r|| <= relTol ||b|| or maxIterations.
/// `project`, when set, removes the null space from residuals (singular A).
/// `applyADot`, when set, is applyA returning p . A p as well (one pass
/// instead of two); without `project` the preconditioner's applyDot() is
/// used likewise.
PcgResult solvePcg(std::size_t size, const std::function<void(const double*, double*)>& applyA,
                   const Preconditioner& preconditioner, const double* b, double* x, double relTol,
                   int maxIterations, const std::function<void(double*)>& project = {},
                   PcgWorkspace* workspace = nullptr,
                   const std::function<double(const double*, double*)>& applyADot = {});

}  // namespace field
}  // namespace lodestone
