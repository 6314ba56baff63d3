// The host reference backend of the field solve: the formulas of
// field_kernels.h in serial loops over host memory. It needs neither TBB nor
// CUDA, so the device backend always has a reference to be compared with.
#include <cmath>
#include <memory>
#include <vector>

#include "field_backend.h"
#include "field_kernels.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
namespace gpu {
namespace detail {

namespace {

class HostFieldBackend final : public FieldBackend {
 public:
  HostFieldBackend() : T_(kernels::makeTables()) {}

  void setProblem(const FieldProblemData& data) override {
    data_ = data;
    fine_.nx = data.grid.dims.i;
    fine_.ny = data.grid.dims.j;
    fine_.nz = data.grid.dims.k;
    fine_.dx = data.grid.dx;
    const std::size_t cells = data.cellBase.size();
    slot_.assign(fine_.cells(), -1);
    for (std::size_t s = 0; s < cells; ++s) {
      int i, j, k;
      fine_.coords(data.cellBase[s], i, j, k);
      slot_[fine_.cellIndex(i, j, k)] = std::int32_t(s);
    }
    local_.assign(cells * 8, 0.0);
    elem_.assign(cells * kernels::kPacked, 0.0);
    tensor_.assign(cells * 6, 0.0);
    levels_.assign(1, fine_);
    coarseD_.clear();
    invDiag_.clear();
  }

  double* allocate(std::size_t n) override {
    storage_.push_back(std::make_unique<std::vector<double>>(n, 0.0));
    return storage_.back()->data();
  }
  void upload(const double* host, std::size_t n, double* dst) override { std::copy(host, host + n, dst); }
  void download(const double* src, std::size_t n, double* host) override { std::copy(src, src + n, host); }

  void fill(std::size_t n, double value, double* x) override { std::fill(x, x + n, value); }
  void copy(std::size_t n, const double* x, double* y) override {
    if (x != y) std::copy(x, x + n, y);
  }
  void axpby(std::size_t n, double a, const double* x, double b, const double* y, double* out) override {
    for (std::size_t m = 0; m < n; ++m) out[m] = a * x[m] + b * y[m];
  }
  double dot(std::size_t n, const double* x, const double* y) override {
    double s = 0;
    for (std::size_t m = 0; m < n; ++m) s += x[m] * y[m];
    return s;
  }
  void jacobi(std::size_t n, double w, const double* d, const double* b, const double* r, double* x) override {
    if (!r) {
      for (std::size_t m = 0; m < n; ++m) x[m] = w * d[m] * b[m];
    } else {
      for (std::size_t m = 0; m < n; ++m) x[m] += w * d[m] * (b[m] - r[m]);
    }
  }
  void removeMean(std::size_t n, double* v) override {
    double s = 0;
    for (std::size_t m = 0; m < n; ++m) s += v[m];
    const double mean = s / double(n);
    for (std::size_t m = 0; m < n; ++m) v[m] -= mean;
  }

  std::size_t nodeCount() const override { return fine_.nodes(); }
  std::size_t materialCellCount() const override { return data_.cellBase.size(); }
  bool shield() const override { return data_.shield; }
  const MagnetizationLaw<double>& law() const override { return data_.law; }

  Evaluation evaluate(const double* phi, double* F, bool jacobian) override {
    return evaluateImpl(phi, F, jacobian, false);
  }
  void residualAtZero(double* F0) override {
    std::vector<double> zero(fine_.nodes(), 0.0);
    evaluateImpl(zero.data(), F0, false, true);
  }
  void applyVacuum(const double* v, double* out) override {
    const kernels::FineView V = view();
    for (std::size_t m = 0; m < fine_.nodes(); ++m) out[m] = kernels::vacuumNode(V, m, v);
  }
  double energyAlong(const double* phi, const double* delta, double lambda, double* absSum) override {
    double s = 0, a = 0;
    for (std::size_t c = 0; c < data_.cellBase.size(); ++c) {
      double pc[8], dc[8], ac = 0;
      for (int q = 0; q < 8; ++q) {
        pc[q] = phi[data_.cellBase[c] + kernels::cornerOffset(fine_, q)];
        dc[q] = delta[data_.cellBase[c] + kernels::cornerOffset(fine_, q)];
      }
      s += kernels::cellEnergyAlong(T_, data_.law, fine_.dx, pc, dc, lambda, &data_.nq[c * 8], &data_.hext[c * 8], &ac);
      a += ac;
    }
    if (absSum) *absSum = a;
    return s;
  }

  void buildPreconditioner(bool multigrid, int coarsestNodes) override {
    const kernels::FineView V = view();
    const std::size_t n = fine_.nodes();
    levels_.assign(1, fine_);
    invDiag_.assign(1, {});
    jacobiInvDiag_.assign(n, 0.0);
    invDiag_[0].assign(n, 0.0);
    for (std::size_t m = 0; m < n; ++m) {
      const double d = kernels::jacobianDiagonalNode(V, m);
      const double inv = d > 0 ? 1.0 / d : 0.0;
      jacobiInvDiag_[m] = inv;
      int i, j, k;
      fine_.coords(m, i, j, k);
      invDiag_[0][m] = V.fixed(i, j, k) ? 0.0 : inv;
    }
    coarseD_.assign(1, {});
    if (!multigrid) return;
    for (;;) {
      const kernels::Dims f = levels_.back();
      if (std::min({f.nx, f.ny, f.nz}) <= coarsestNodes) break;
      const kernels::Dims c = kernels::coarser(f);
      const std::size_t level = levels_.size();
      std::vector<double> D(c.cells() * 6, 0.0);
      for (int K = 0; K < c.nz - 1; ++K)
        for (int J = 0; J < c.ny - 1; ++J)
          for (int I = 0; I < c.nx - 1; ++I) {
            double* out = &D[c.cellIndex(I, J, K) * 6];
            if (level == 1) {
              kernels::coarseTensor(
                  f, I, J, K,
                  [&](std::size_t cell) -> const double* {
                    return slot_[cell] >= 0 ? &tensor_[std::size_t(slot_[cell]) * 6] : nullptr;
                  },
                  out);
            } else {
              const std::vector<double>& fd = coarseD_[level - 1];
              kernels::coarseTensor(
                  f, I, J, K,
                  [&](std::size_t cell) -> const double* {
                    return kernels::isZeroTensor(&fd[cell * 6]) ? nullptr : &fd[cell * 6];
                  },
                  out);
            }
          }
      levels_.push_back(c);
      coarseD_.push_back(std::move(D));
      const kernels::CoarseView CV = coarseView(int(level));
      std::vector<double> inv(c.nodes());
      for (std::size_t m = 0; m < c.nodes(); ++m) inv[m] = kernels::coarseInverseDiagonalNode(T_, CV, m);
      invDiag_.push_back(std::move(inv));
    }
  }
  int levelCount() const override { return int(levels_.size()); }
  std::size_t levelNodes(int level) const override { return levels_[std::size_t(level)].nodes(); }
  void applyLevel(int level, const double* v, double* out) override {
    if (level == 0) {
      const kernels::FineView V = view();
      for (std::size_t m = 0; m < fine_.nodes(); ++m) out[m] = kernels::jacobianNode(V, m, v);
      return;
    }
    const kernels::CoarseView CV = coarseView(level);
    for (std::size_t m = 0; m < CV.g.nodes(); ++m) out[m] = kernels::coarseNode(T_, CV, m, v);
  }
  void zeroFixed(int level, double* v) override {
    if (data_.shield) return;
    const kernels::Dims& g = levels_[std::size_t(level)];
    for (std::size_t m = 0; m < g.nodes(); ++m) {
      int i, j, k;
      g.coords(m, i, j, k);
      if (g.isWall(i, j, k)) v[m] = 0.0;
    }
  }
  const double* inverseDiagonal(int level, bool jacobiPreconditioner) override {
    return jacobiPreconditioner ? jacobiInvDiag_.data() : invDiag_[std::size_t(level)].data();
  }
  void restrictTo(int fineLevel, const double* fine, double* coarse) override {
    const kernels::Dims& f = levels_[std::size_t(fineLevel)];
    const kernels::Dims& c = levels_[std::size_t(fineLevel) + 1];
    for (std::size_t m = 0; m < c.nodes(); ++m) {
      int I, J, K;
      c.coords(m, I, J, K);
      coarse[m] = kernels::restrictAt(f, I, J, K, fine);
    }
  }
  void prolong(int fineLevel, const double* coarse, double* fine) override {
    const kernels::Dims& f = levels_[std::size_t(fineLevel)];
    const kernels::Dims& c = levels_[std::size_t(fineLevel) + 1];
    for (std::size_t m = 0; m < f.nodes(); ++m) {
      int i, j, k;
      f.coords(m, i, j, k);
      fine[m] = kernels::prolongAt(c, i, j, k, coarse);
    }
  }
  double* work(int level, int slot) override {
    require(slot >= 0 && slot < kWorkSlots, "field solve: work slot ", slot, " out of range");
    if (work_.size() <= std::size_t(level)) work_.resize(std::size_t(level) + 1);
    auto& slots = work_[std::size_t(level)];
    if (slots.size() < std::size_t(kWorkSlots)) slots.resize(std::size_t(kWorkSlots));
    auto& v = slots[std::size_t(slot)];
    const std::size_t n = levelNodes(level);
    if (v.size() != n) v.assign(n, 0.0);
    return v.data();
  }
  const char* name() const override { return "host"; }

 private:
  kernels::FineView view() const {
    kernels::FineView V;
    V.g = fine_;
    V.shield = data_.shield;
    V.slot = slot_.data();
    V.local = local_.data();
    V.elem = elem_.data();
    return V;
  }
  kernels::CoarseView coarseView(int level) const {
    kernels::CoarseView V;
    V.g = levels_[std::size_t(level)];
    V.shield = data_.shield;
    V.D = coarseD_[std::size_t(level)].data();
    return V;
  }
  Evaluation evaluateImpl(const double* phi, double* F, bool jacobian, bool atZero) {
    Evaluation e;
    const std::size_t cells = data_.cellBase.size();
    std::vector<double> savedLocal;
    if (atZero) savedLocal = local_;  // residualAtZero leaves the state of the last evaluate
    for (std::size_t c = 0; c < cells; ++c) {
      double pc[8];
      for (int q = 0; q < 8; ++q) pc[q] = phi[data_.cellBase[c] + kernels::cornerOffset(fine_, q)];
      const kernels::CellResult r =
          kernels::evaluateCell(T_, data_.law, fine_.dx, pc, &data_.nq[c * 8], &data_.hext[c * 8], atZero,
                                jacobian ? &elem_[c * kernels::kPacked] : nullptr,
                                jacobian ? reinterpret_cast<SymMat3d*>(&tensor_[c * 6]) : nullptr);
      for (int q = 0; q < 8; ++q) local_[c * 8 + std::size_t(q)] = r.local[q];
      e.energy += r.energy;
      e.energyAbs += r.energyAbs;
      e.finite = e.finite && r.finite;
    }
    const kernels::FineView V = view();
    for (std::size_t m = 0; m < fine_.nodes(); ++m) F[m] = kernels::residualNode(V, m, phi);
    if (atZero) local_.swap(savedLocal);
    return e;
  }

  kernels::Tables T_;
  FieldProblemData data_;
  kernels::Dims fine_;
  std::vector<std::int32_t> slot_;
  std::vector<double> local_, elem_, tensor_;
  std::vector<kernels::Dims> levels_;
  std::vector<std::vector<double>> coarseD_;  // [0] unused
  std::vector<std::vector<double>> invDiag_;
  std::vector<double> jacobiInvDiag_;
  std::vector<std::vector<std::vector<double>>> work_;
  std::vector<std::unique_ptr<std::vector<double>>> storage_;
};

}  // namespace

std::unique_ptr<FieldBackend> makeHostFieldBackend() { return std::make_unique<HostFieldBackend>(); }

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
