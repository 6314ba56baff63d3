#include "lodestone/core/stage/nodal_field.h"

#include <vector>

#include <tbb/parallel_for.h>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace stage {

namespace {
// Node (i,j,k) index arithmetic along one axis.
struct AxisStep {
  int count;
  std::ptrdiff_t stride;
};
inline AxisStep axisStep(const GridSpec& g, int axis) {
  if (axis == 0) return {g.dims.i, 1};
  if (axis == 1) return {g.dims.j, std::ptrdiff_t(g.dims.i)};
  return {g.dims.k, std::ptrdiff_t(g.dims.i) * g.dims.j};
}
inline int coord(int i, int j, int k, int axis) { return axis == 0 ? i : (axis == 1 ? j : k); }

// dst = central difference (axis) of src divided by dx; one-sided at walls.
void differenceAlong(const GridSpec& g, const double* src, double* dst, int axis) {
  const AxisStep a = axisStep(g, axis);
  const double inv2h = 0.5 / g.dx, invh = 1.0 / g.dx;
  tbb::parallel_for(0, g.dims.k, [&](int k) {
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        const std::size_t m = g.index(i, j, k);
        const int p = coord(i, j, k, axis);
        if (p == 0)
          dst[m] = (src[m + std::size_t(a.stride)] - src[m]) * invh;
        else if (p == a.count - 1)
          dst[m] = (src[m] - src[m - std::size_t(a.stride)]) * invh;
        else
          dst[m] = (src[m + std::size_t(a.stride)] - src[m - std::size_t(a.stride)]) * inv2h;
      }
  });
}

// dst = [1/6, 2/3, 1/6] smoothing of src along axis ([2/3, 1/3] at walls).
void smoothAlong(const GridSpec& g, const double* src, double* dst, int axis) {
  const AxisStep a = axisStep(g, axis);
  tbb::parallel_for(0, g.dims.k, [&](int k) {
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        const std::size_t m = g.index(i, j, k);
        const int p = coord(i, j, k, axis);
        if (p == 0)
          dst[m] = (2.0 / 3) * src[m] + (1.0 / 3) * src[m + std::size_t(a.stride)];
        else if (p == a.count - 1)
          dst[m] = (2.0 / 3) * src[m] + (1.0 / 3) * src[m - std::size_t(a.stride)];
        else
          dst[m] = (2.0 / 3) * src[m] + (1.0 / 6) * (src[m + std::size_t(a.stride)] + src[m - std::size_t(a.stride)]);
      }
  });
}
}  // namespace

void projectedGradient(GridView<const double> phi, GridView<Vec3d> gradient, GridScratch* scratch) {
  require(phi.spec == gradient.spec, "projectedGradient: grids differ");
  const GridSpec& g = phi.spec;
  const std::size_t n = g.nodeCount();
  GridScratch local;
  GridScratch& s = scratch ? *scratch : local;
  s.scalar0.resize(n);  // every value is written before it is read
  s.scalar1.resize(n);
  std::vector<double>&a = s.scalar0, &b = s.scalar1;
  for (int axis = 0; axis < 3; ++axis) {
    const int s1 = (axis + 1) % 3, s2 = (axis + 2) % 3;
    differenceAlong(g, phi.data, a.data(), axis);
    smoothAlong(g, a.data(), b.data(), s1);
    smoothAlong(g, b.data(), a.data(), s2);
    tbb::parallel_for(std::size_t(0), n, std::size_t(1) << 14, [&](std::size_t m0) {
      const std::size_t m1 = std::min(n, m0 + (std::size_t(1) << 14));
      for (std::size_t m = m0; m < m1; ++m) gradient[m][axis] = a[m];
    });
  }
}

void recoverNodalFields(GridView<const double> phi, GridView<const Vec3d> Hext, GridView<const double> n,
                        const MagnetizationLaw<double>& law, GridView<Vec3d> H, GridView<Vec3d> M,
                        GridView<Vec3d> B, GridScratch* scratch) {
  const GridSpec& g = phi.spec;
  require(Hext.spec == g && n.spec == g, "recoverNodalFields: input grids differ");
  GridScratch local;
  GridScratch& s = scratch ? *scratch : local;
  s.vector0.resize(g.nodeCount());
  const std::vector<Vec3d>& grad = s.vector0;
  projectedGradient(phi, GridView<Vec3d>{s.vector0.data(), g}, &s);
  const std::size_t count = g.nodeCount();
  tbb::parallel_for(std::size_t(0), count, std::size_t(1) << 12, [&](std::size_t m0) {
    const std::size_t m1 = std::min(count, m0 + (std::size_t(1) << 12));
    for (std::size_t m = m0; m < m1; ++m) {
      const Vec3d h = Hext[m] - grad[m];
      // Empty nodes (most of a grid) skip the Langevin function: with n = 0
      // it returns (0 * g) H = 0 * H for finite H, bit for bit.
      const bool skip = n[m] == 0 && law.kind == LawKind::Langevin && isFinite(h);
      const Vec3d mag = skip ? 0.0 * h : magnetization(law, n[m], h);
      if (H.data) H[m] = h;
      if (M.data) M[m] = mag;
      if (B.data) B[m] = kMu0 * (h + mag);
    }
  });
}

}  // namespace stage
}  // namespace lodestone
