#include "lodestone/gpu/field_solver.h"

#include <algorithm>
#include <cmath>

#include "field_backend.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/q1_element.h"
#include "device_solve_backend.h"
#include "lodestone/core/base/stopwatch.h"
#include "lodestone/core/field/newton_solver.h"
#include "lodestone/core/field/wall_clearance.h"

namespace lodestone {
namespace gpu {

struct FieldSolver::Impl {
  std::unique_ptr<detail::FieldBackend> backend;
  std::size_t cells = 0;
  int wallClearance = 1 << 30;  ///< cells between the material and the open wall
};

FieldSolver::FieldSolver(const GridSpec& grid, const MagnetizationLaw<double>& law, BoundaryKind boundary,
                         Backend backend)
    : grid_(grid), law_(law), boundary_(boundary), impl_(std::make_unique<Impl>()) {
  grid_.validate("gpu field-solve grid");
  require(boundary != BoundaryKind::Open || (grid.dims.i >= 3 && grid.dims.j >= 3 && grid.dims.k >= 3),
          "gpu field-solve grid: the open boundary needs at least 3 nodes per axis, got ", grid.dims.i, " x ",
          grid.dims.j, " x ", grid.dims.k);
  require(grid_.cellCount() < std::size_t(1) << 31, "gpu field-solve grid: ", grid_.cellCount(),
          " cells is too many (at most 2^31 - 1)");
  backend_ = resolveBackend(backend, &backendMessage_);
  impl_->backend = backend_ == Backend::Cuda ? detail::makeDeviceFieldBackend() : detail::makeHostFieldBackend();
}

FieldSolver::~FieldSolver() = default;

std::size_t FieldSolver::materialCellCount() const { return impl_->cells; }

namespace detail {
FieldProblemData prepareProblem(const GridSpec& g, const MagnetizationLaw<double>& law, bool shield, const double* n,
                                const AppliedField& appliedField) {
  require(n != nullptr, "gpu field solve: no density array given");
  require(bool(appliedField), "gpu field solve: no applied-field function given");
  const std::size_t count = g.nodeCount();
  const std::size_t nx = std::size_t(g.dims.i), ny = std::size_t(g.dims.j);
  for (std::size_t m = 0; m < count; ++m)
    if (!(std::isfinite(n[m]) && n[m] >= 0))
      throw InvalidArgument(concat("gpu field solve: micro-particle density n at node (", m % nx, ", ", (m / nx) % ny,
                                   ", ", m / (nx * ny), ") is ", n[m], " 1/m^3; it must be finite and >= 0"));
  FieldProblemData data;
  data.grid = g;
  data.law = law;
  data.shield = shield;
  std::size_t off[8];
  for (int c = 0; c < 8; ++c) off[c] = std::size_t(c & 1) + nx * (std::size_t((c >> 1) & 1) + ny * std::size_t(c >> 2));
  const Index3 cd = g.cellDims();
  for (int k = 0; k < cd.k; ++k)
    for (int j = 0; j < cd.j; ++j)
      for (int i = 0; i < cd.i; ++i) {
        const std::size_t base = g.index(i, j, k);
        bool any = false;
        for (int c = 0; c < 8 && !any; ++c) any = n[base + off[c]] > 0;
        if (any) data.cellBase.push_back(base);
      }
  const std::size_t cells = data.cellBase.size();
  data.nq.resize(cells * 8);
  data.hext.resize(cells * 8);
  std::vector<Vec3d> x(cells * 8);
  const q1::Tables T = q1::makeTables();
  for (std::size_t s = 0; s < cells; ++s) {
    double nc[8];
    for (int c = 0; c < 8; ++c) nc[c] = n[data.cellBase[s] + off[c]];
    const std::size_t b = data.cellBase[s];
    const Vec3d o = g.nodePosition(int(b % nx), int((b / nx) % ny), int(b / (nx * ny)));
    for (int q = 0; q < 8; ++q) {
      data.nq[s * 8 + std::size_t(q)] = q1::interpolate(T, q, nc);
      x[s * 8 + std::size_t(q)] =
          o + g.dx * Vec3d{q1::gaussAbscissa(q & 1), q1::gaussAbscissa((q >> 1) & 1), q1::gaussAbscissa((q >> 2) & 1)};
    }
  }
  if (cells > 0) appliedField(x.data(), x.size(), data.hext.data());
  for (std::size_t m = 0; m < cells * 8; ++m)
    if (!isFinite(data.hext[m]))
      throw InvalidArgument(
          concat("gpu field solve: the applied field is not finite at (", x[m].x, ", ", x[m].y, ", ", x[m].z, ") m"));
  return data;
}
}  // namespace detail

void FieldSolver::setMaterial(const double* n, const AppliedField& appliedField) {
  const detail::FieldProblemData data =
      detail::prepareProblem(grid_, law_, boundary_ == BoundaryKind::Shield, n, appliedField);
  impl_->backend->setProblem(data);
  impl_->cells = data.cellBase.size();
  impl_->wallClearance = materialWallClearance(grid_, data.cellBase.data(), data.cellBase.size());
}

FieldSolveReport FieldSolver::solve(double* phi, const FieldSolveSettings& settings) {
  require(phi != nullptr, "gpu field solve: no potential array given");
  settings.validate();
  const auto t0 = SteadyClock::now();
  detail::FieldBackend& be = *impl_->backend;
  const std::size_t n = grid_.nodeCount();
  bool finite = true, cold = true;
  for (std::size_t m = 0; m < n && finite; ++m) {
    finite = std::isfinite(phi[m]);
    cold = cold && phi[m] == 0.0;
  }
  if (!finite) std::fill(phi, phi + n, 0.0);  // a poisoned warm start is discarded
  cold = cold || !finite;
  double* dphi = be.work(0, 0);
  be.upload(phi, n, dphi);
  const bool open = boundary_ == BoundaryKind::Open;
  detail::DeviceSolveBackend backend(be, grid_, settings, dphi, cold, impl_->wallClearance,
                                     open ? wallValues_ : WallUpdate{}, open ? wallMove_ : WallUpdate{});
  FieldSolveReport rep = NewtonSolver(backend, settings).solve();
  be.download(backend.phi(), n, phi);
  rep.seconds = secondsSince(t0);
  return rep;
}

}  // namespace gpu
}  // namespace lodestone
