// The CUDA backend of the field solve and of the magnetic force: the
// formulas of field_kernels.h launched one thread per node or per material
// cell over device-resident arrays. Per Newton step only scalars (dot
// products, energies) come back to the host.
#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "device_common.cuh"
#include "device_entry.h"
#include "device_query.h"
#include "field_backend.h"
#include "field_kernels.h"

namespace lodestone {
namespace gpu {
namespace detail {

__constant__ kernels::Tables c_tables;

/// FieldBackend over device memory. Public members only: the extended
/// lambdas of its member functions must be defined in accessible functions.
class DeviceFieldBackend final : public FieldBackend {
 public:
  DeviceFieldBackend() {
    std::string status;
    if (!queryDevice(status)) throw Error(concat("gpu field solve: no usable CUDA device (", status, ")"));
    const kernels::Tables t = kernels::makeTables();
    LODESTONE_CUDA_CHECK(cudaMemcpyToSymbol(c_tables, &t, sizeof(t)));
  }

  void setProblem(const FieldProblemData& data) override {
    shield_ = data.shield;
    law_ = data.law;
    fine_.nx = data.grid.dims.i;
    fine_.ny = data.grid.dims.j;
    fine_.nz = data.grid.dims.k;
    fine_.dx = data.grid.dx;
    cells_ = data.cellBase.size();
    std::vector<std::int32_t> slot(fine_.cells(), -1);
    for (std::size_t s = 0; s < cells_; ++s) {
      int i, j, k;
      fine_.coords(data.cellBase[s], i, j, k);
      slot[fine_.cellIndex(i, j, k)] = std::int32_t(s);
    }
    slot_.upload(slot.data(), slot.size());
    cellBase_.upload(data.cellBase.data(), cells_);
    nq_.upload(data.nq.data(), data.nq.size());
    hext_.upload(data.hext.data(), data.hext.size());
    local_.resize(cells_ * 8);
    local_.zero();
    elem_.resize(cells_ * kernels::kPacked);
    elem_.zero();
    tensor_.resize(cells_ * 6);
    tensor_.zero();
    cellEnergy_.resize(cells_ * 3);
    levels_.assign(1, fine_);
    coarseD_.clear();
    coarseD_.resize(1);
    invDiag_.clear();
    invDiag_.resize(1);
  }

  double* allocate(std::size_t n) override {
    storage_.push_back(std::make_unique<DeviceBuffer<double>>(n));
    storage_.back()->zero();
    return storage_.back()->data();
  }
  void upload(const double* host, std::size_t n, double* dst) override {
    LODESTONE_CUDA_CHECK(cudaMemcpy(dst, host, n * sizeof(double), cudaMemcpyHostToDevice));
  }
  void download(const double* src, std::size_t n, double* host) override {
    LODESTONE_CUDA_CHECK(cudaMemcpy(host, src, n * sizeof(double), cudaMemcpyDeviceToHost));
  }

  void fill(std::size_t n, double value, double* x) override {
    forEach(n, [=] __device__(std::size_t m) { x[m] = value; });
  }
  void copy(std::size_t n, const double* x, double* y) override {
    if (x != y) LODESTONE_CUDA_CHECK(cudaMemcpy(y, x, n * sizeof(double), cudaMemcpyDeviceToDevice));
  }
  void axpby(std::size_t n, double a, const double* x, double b, const double* y, double* out) override {
    forEach(n, [=] __device__(std::size_t m) { out[m] = a * x[m] + b * y[m]; });
  }
  double dot(std::size_t n, const double* x, const double* y) override {
    return reducer_.sum(n, [=] __device__(std::size_t m) { return x[m] * y[m]; });
  }
  void jacobi(std::size_t n, double w, const double* d, const double* b, const double* r, double* x) override {
    if (!r)
      forEach(n, [=] __device__(std::size_t m) { x[m] = w * d[m] * b[m]; });
    else
      forEach(n, [=] __device__(std::size_t m) { x[m] += w * d[m] * (b[m] - r[m]); });
  }
  void removeMean(std::size_t n, double* v) override {
    const double mean = reducer_.sum(n, [=] __device__(std::size_t m) { return v[m]; }) / double(n);
    forEach(n, [=] __device__(std::size_t m) { v[m] -= mean; });
  }

  std::size_t nodeCount() const override { return fine_.nodes(); }
  std::size_t materialCellCount() const override { return cells_; }
  bool shield() const override { return shield_; }
  const MagnetizationLaw<double>& law() const override { return law_; }

  Evaluation evaluate(const double* phi, double* F, bool jacobian) override {
    return evaluateImpl(phi, F, jacobian, false);
  }
  void residualAtZero(double* F0) override {
    if (zeros_.size() != fine_.nodes()) {
      zeros_.resize(fine_.nodes());
      zeros_.zero();
    }
    evaluateImpl(zeros_.data(), F0, false, true);
  }
  void applyVacuum(const double* v, double* out) override {
    const kernels::FineView V = view();
    forEach(fine_.nodes(), [=] __device__(std::size_t m) { out[m] = kernels::vacuumNode(V, m, v); });
  }
  double energyAlong(const double* phi, const double* delta, double lambda, double* absSum) override {
    const kernels::Dims g = fine_;
    const MagnetizationLaw<double> law = law_;
    const std::size_t* base = cellBase_.data();
    const double* nq = nq_.data();
    const Vec3d* hext = hext_.data();
    double* e = cellEnergy_.data();
    const std::size_t cells = cells_;
    forEach(cells, [=] __device__(std::size_t c) {
      double pc[8], dc[8], a = 0;
      for (int q = 0; q < 8; ++q) {
        pc[q] = phi[base[c] + kernels::cornerOffset(g, q)];
        dc[q] = delta[base[c] + kernels::cornerOffset(g, q)];
      }
      e[c] = kernels::cellEnergyAlong(c_tables, law, g.dx, pc, dc, lambda, nq + c * 8, hext + c * 8, &a);
      e[cells + c] = a;
    });
    const double s = reducer_.sum(cells, [=] __device__(std::size_t c) { return e[c]; });
    if (absSum) *absSum = reducer_.sum(cells, [=] __device__(std::size_t c) { return e[cells + c]; });
    return s;
  }

  void buildPreconditioner(bool multigrid, int coarsestNodes) override {
    const kernels::FineView V = view();
    const std::size_t n = fine_.nodes();
    levels_.assign(1, fine_);
    coarseD_.resize(1);
    invDiag_.resize(1);
    invDiag_[0].resize(n);
    jacobiInvDiag_.resize(n);
    double* inv0 = invDiag_[0].data();
    double* invJ = jacobiInvDiag_.data();
    forEach(n, [=] __device__(std::size_t m) {
      const double d = kernels::jacobianDiagonalNode(V, m);
      const double inv = d > 0 ? 1.0 / d : 0.0;
      invJ[m] = inv;
      int i, j, k;
      V.g.coords(m, i, j, k);
      inv0[m] = V.fixed(i, j, k) ? 0.0 : inv;
    });
    hostLevel_ = -1;
    if (!multigrid) return;
    for (;;) {
      const kernels::Dims f = levels_.back();
      if (std::min({f.nx, f.ny, f.nz}) <= coarsestNodes) break;
      const kernels::Dims c = kernels::coarser(f);
      const std::size_t level = levels_.size();
      coarseD_.emplace_back(c.cells() * 6);
      invDiag_.emplace_back(c.nodes());
      levels_.push_back(c);
      double* D = coarseD_[level].data();
      if (level == 1) {
        const std::int32_t* slot = slot_.data();
        const double* tensor = tensor_.data();
        forEach(c.cells(), [=] __device__(std::size_t cell) {
          const int I = int(cell % std::size_t(c.nx - 1)),
                    J = int((cell / std::size_t(c.nx - 1)) % std::size_t(c.ny - 1)),
                    K = int(cell / (std::size_t(c.nx - 1) * std::size_t(c.ny - 1)));
          kernels::coarseTensor(
              f, I, J, K,
              [&](std::size_t fc) -> const double* {
                return slot[fc] >= 0 ? tensor + std::size_t(slot[fc]) * 6 : nullptr;
              },
              D + cell * 6);
        });
      } else {
        const double* fd = coarseD_[level - 1].data();
        forEach(c.cells(), [=] __device__(std::size_t cell) {
          const int I = int(cell % std::size_t(c.nx - 1)),
                    J = int((cell / std::size_t(c.nx - 1)) % std::size_t(c.ny - 1)),
                    K = int(cell / (std::size_t(c.nx - 1) * std::size_t(c.ny - 1)));
          kernels::coarseTensor(
              f, I, J, K,
              [&](std::size_t fc) -> const double* {
                return kernels::isZeroTensor(fd + fc * 6) ? nullptr : fd + fc * 6;
              },
              D + cell * 6);
        });
      }
      const kernels::CoarseView CV = coarseView(int(level));
      double* inv = invDiag_[level].data();
      forEach(c.nodes(),
              [=] __device__(std::size_t m) { inv[m] = kernels::coarseInverseDiagonalNode(c_tables, CV, m); });
    }
  }
  /// The coarsest grid (a few hundred nodes) on the host: its CG would
  /// otherwise be dozens of tiny launches and host synchronisations per cycle.
  bool solveCoarsest(int level, const double* b, double* x) override {
    if (level == 0 || level + 1 != int(levels_.size())) return false;
    const kernels::Dims g = levels_[std::size_t(level)];
    const std::size_t n = g.nodes();
    if (hostD_.size() != g.cells() * 6 || hostLevel_ != level) {
      hostD_.resize(g.cells() * 6);
      coarseD_[std::size_t(level)].download(hostD_.data(), hostD_.size());
      hostInv_.resize(n);
      invDiag_[std::size_t(level)].download(hostInv_.data(), n);
      hostLevel_ = level;
    }
    hb_.resize(n);
    hx_.assign(n, 0.0);
    download(b, n, hb_.data());
    kernels::CoarseView V;
    V.g = g;
    V.shield = shield_;
    V.D = hostD_.data();
    const auto apply = [&](const std::vector<double>& v, std::vector<double>& out) {
      for (std::size_t m = 0; m < n; ++m) out[m] = kernels::coarseNode(hostTables_, V, m, v.data());
    };
    const auto dotH = [&](const std::vector<double>& u, const std::vector<double>& v) {
      double s = 0;
      for (std::size_t m = 0; m < n; ++m) s += u[m] * v[m];
      return s;
    };
    const auto project = [&](std::vector<double>& v) {
      if (!shield_) return;
      double s = 0;
      for (std::size_t m = 0; m < n; ++m) s += v[m];
      const double mean = s / double(n);
      for (std::size_t m = 0; m < n; ++m) v[m] -= mean;
    };
    std::vector<double> r = hb_, z(n), p(n), Ap(n);
    project(r);
    const double bnorm = std::sqrt(dotH(r, r));
    if (bnorm > 0) {
      for (std::size_t m = 0; m < n; ++m) z[m] = hostInv_[m] * r[m];
      project(z);
      p = z;
      double rz = dotH(r, z);
      for (int it = 0; it < 10 * int(n); ++it) {
        apply(p, Ap);
        const double pAp = dotH(p, Ap);
        if (!(pAp > 0) || !std::isfinite(pAp) || !std::isfinite(rz)) break;
        const double alpha = rz / pAp;
        for (std::size_t m = 0; m < n; ++m) {
          hx_[m] = hx_[m] + alpha * p[m];
          r[m] = r[m] - alpha * Ap[m];
        }
        project(r);
        if (std::sqrt(dotH(r, r)) <= 1e-10 * bnorm) break;
        for (std::size_t m = 0; m < n; ++m) z[m] = hostInv_[m] * r[m];
        project(z);
        const double rzNew = dotH(r, z);
        const double beta = rzNew / rz;
        rz = rzNew;
        for (std::size_t m = 0; m < n; ++m) p[m] = z[m] + beta * p[m];
      }
      project(hx_);
    }
    upload(hx_.data(), n, x);
    return true;
  }
  int levelCount() const override { return int(levels_.size()); }
  std::size_t levelNodes(int level) const override { return levels_[std::size_t(level)].nodes(); }
  void applyLevel(int level, const double* v, double* out) override {
    if (level == 0) {
      const kernels::FineView V = view();
      forEach(fine_.nodes(), [=] __device__(std::size_t m) { out[m] = kernels::jacobianNode(V, m, v); });
      return;
    }
    const kernels::CoarseView CV = coarseView(level);
    forEach(CV.g.nodes(), [=] __device__(std::size_t m) { out[m] = kernels::coarseNode(c_tables, CV, m, v); });
  }
  void zeroFixed(int level, double* v) override {
    if (shield_) return;
    const kernels::Dims g = levels_[std::size_t(level)];
    forEach(g.nodes(), [=] __device__(std::size_t m) {
      int i, j, k;
      g.coords(m, i, j, k);
      if (g.isWall(i, j, k)) v[m] = 0.0;
    });
  }
  const double* inverseDiagonal(int level, bool jacobiPreconditioner) override {
    return jacobiPreconditioner ? jacobiInvDiag_.data() : invDiag_[std::size_t(level)].data();
  }
  void restrictTo(int fineLevel, const double* fine, double* coarse) override {
    const kernels::Dims f = levels_[std::size_t(fineLevel)];
    const kernels::Dims c = levels_[std::size_t(fineLevel) + 1];
    forEach(c.nodes(), [=] __device__(std::size_t m) {
      int I, J, K;
      c.coords(m, I, J, K);
      coarse[m] = kernels::restrictAt(f, I, J, K, fine);
    });
  }
  void prolong(int fineLevel, const double* coarse, double* fine) override {
    const kernels::Dims f = levels_[std::size_t(fineLevel)];
    const kernels::Dims c = levels_[std::size_t(fineLevel) + 1];
    forEach(f.nodes(), [=] __device__(std::size_t m) {
      int i, j, k;
      f.coords(m, i, j, k);
      fine[m] = kernels::prolongAt(c, i, j, k, coarse);
    });
  }
  double* work(int level, int slot) override {
    require(slot >= 0 && slot < kWorkSlots, "gpu field solve: work slot ", slot, " out of range");
    if (work_.size() <= std::size_t(level)) work_.resize(std::size_t(level) + 1);
    auto& slots = work_[std::size_t(level)];
    if (slots.size() < std::size_t(kWorkSlots)) slots.resize(std::size_t(kWorkSlots));
    DeviceBuffer<double>& b = slots[std::size_t(slot)];
    const std::size_t n = levelNodes(level);
    if (b.size() != n) {
      b.resize(n);
      b.zero();
    }
    return b.data();
  }
  const char* name() const override { return "cuda"; }

  kernels::FineView view() const {
    kernels::FineView V;
    V.g = fine_;
    V.shield = shield_;
    V.slot = slot_.data();
    V.local = local_.data();
    V.elem = elem_.data();
    return V;
  }
  kernels::CoarseView coarseView(int level) const {
    kernels::CoarseView V;
    V.g = levels_[std::size_t(level)];
    V.shield = shield_;
    V.D = coarseD_[std::size_t(level)].data();
    return V;
  }

  Evaluation evaluateImpl(const double* phi, double* F, bool jacobian, bool atZero) {
    const kernels::Dims g = fine_;
    const MagnetizationLaw<double> law = law_;
    const std::size_t* base = cellBase_.data();
    const double* nq = nq_.data();
    const Vec3d* hext = hext_.data();
    double* local = local_.data();
    double* elem = jacobian ? elem_.data() : nullptr;
    double* tensor = tensor_.data();
    double* e = cellEnergy_.data();
    const std::size_t cells = cells_;
    forEach(cells, [=] __device__(std::size_t c) {
      double pc[8];
      for (int q = 0; q < 8; ++q) pc[q] = phi[base[c] + kernels::cornerOffset(g, q)];
      double E[kernels::kPacked];
      SymMat3d t;
      const kernels::CellResult r = kernels::evaluateCell(c_tables, law, g.dx, pc, nq + c * 8, hext + c * 8, atZero,
                                                          elem ? E : nullptr, elem ? &t : nullptr);
      for (int q = 0; q < 8; ++q) local[c * 8 + std::size_t(q)] = r.local[q];
      if (elem) {
        for (int x = 0; x < kernels::kPacked; ++x) elem[c * kernels::kPacked + std::size_t(x)] = E[x];
        tensor[c * 6 + 0] = t.xx;
        tensor[c * 6 + 1] = t.yy;
        tensor[c * 6 + 2] = t.zz;
        tensor[c * 6 + 3] = t.xy;
        tensor[c * 6 + 4] = t.xz;
        tensor[c * 6 + 5] = t.yz;
      }
      e[c] = r.energy;
      e[cells + c] = r.energyAbs;
      e[2 * cells + c] = r.finite ? 0.0 : 1.0;
    });
    const kernels::FineView V = view();
    forEach(g.nodes(), [=] __device__(std::size_t m) { F[m] = kernels::residualNode(V, m, phi); });
    Evaluation out;
    if (atZero) return out;
    out.energy = reducer_.sum(cells, [=] __device__(std::size_t c) { return e[c]; });
    out.energyAbs = reducer_.sum(cells, [=] __device__(std::size_t c) { return e[cells + c]; });
    out.finite = reducer_.sum(cells, [=] __device__(std::size_t c) { return e[2 * cells + c]; }) == 0.0;
    return out;
  }

  kernels::Dims fine_;
  bool shield_ = true;
  MagnetizationLaw<double> law_;
  std::size_t cells_ = 0;
  DeviceBuffer<std::int32_t> slot_;
  DeviceBuffer<std::size_t> cellBase_;
  DeviceBuffer<double> nq_;
  DeviceBuffer<Vec3d> hext_;
  DeviceBuffer<double> local_, elem_, tensor_, cellEnergy_, zeros_;
  std::vector<kernels::Dims> levels_;
  std::vector<DeviceBuffer<double>> coarseD_, invDiag_;
  DeviceBuffer<double> jacobiInvDiag_;
  std::vector<std::vector<DeviceBuffer<double>>> work_;
  std::vector<std::unique_ptr<DeviceBuffer<double>>> storage_;
  Reducer reducer_;
  kernels::Tables hostTables_ = kernels::makeTables();
  std::vector<double> hostD_, hostInv_, hb_, hx_;
  int hostLevel_ = -1;
};

std::unique_ptr<FieldBackend> makeDeviceFieldBackend() { return std::make_unique<DeviceFieldBackend>(); }

void deviceMagneticForce(const kernels::Dims& g, const MagnetizationLaw<double>& law, const MagneticForceInput& in,
                         const MagneticForceOutput& out) {
  std::string status;
  if (!queryDevice(status)) throw Error(concat("gpu magnetic force: no usable CUDA device (", status, ")"));
  const std::size_t count = g.nodes();
  DeviceBuffer<double> phi, n;
  DeviceBuffer<Vec3d> hext, H(count), B(count), a(count), b(count);
  phi.upload(in.phi, count);
  n.upload(in.n, count);
  hext.upload(in.hext, count);
  const double* dphi = phi.data();
  const double* dn = n.data();
  const Vec3d* dh = hext.data();
  Vec3d* dH = H.data();
  Vec3d* dB = B.data();
  forEach(count, [=] __device__(std::size_t m) { kernels::nodalFieldsAt(g, law, dphi, dh, dn, m, dH[m], dB[m]); });
  if (out.H) H.download(out.H, count);
  if (out.B) B.download(out.B, count);
  if (!out.force) return;
  const bool mask = in.maskMaterial;
  const int dilation = in.dilation;
  Vec3d* pa = a.data();
  Vec3d* pb = b.data();
  forEach(count,
          [=] __device__(std::size_t m) { pa[m] = kernels::stressDivergenceAt(g, dH, dB, dh, dn, mask, dilation, m); });
  for (int axis = 0; axis < 3; ++axis) {
    const Vec3d* src = pa;
    Vec3d* dst = pb;
    forEach(count, [=] __device__(std::size_t m) { dst[m] = kernels::spreadAxisAt(g, src, axis, m); });
    std::swap(pa, pb);
  }
  LODESTONE_CUDA_CHECK(cudaMemcpy(out.force, pa, count * sizeof(Vec3d), cudaMemcpyDeviceToHost));
}

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
