#include "lodestone/core/stage/nodal_field.h"

#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "plane_sweep.h"

namespace lodestone {
inline namespace stage {

namespace {

// The projected gradient is computed z plane by z plane (nx * ny nodes each),
// chunks of planes in parallel, each value by the same operations in the
// same order as three separate whole-grid passes per component would
// (difference along the component's axis, then smoothing along the next axis,
// then along the one after), so the same bits; the intermediate values live
// in a few planes per thread instead of whole grids.

// Where a node lies along the axis of an operation: on the first wall, the
// last, or between (where both neighbours exist).
enum class Along { First, Last, Inner };

// The two operations at one node from its value and its neighbours' along
// the axis (a missing neighbour is passed as 0 and not used): the central
// difference / dx, one-sided at the walls; the [1/6, 2/3, 1/6] smoothing,
// [2/3, 1/3] at the walls.
struct Difference {
  double invh, inv2h;
  explicit Difference(double dx) : invh(1.0 / dx), inv2h(0.5 / dx) {}
  double operator()(double below, double centre, double above, Along at) const {
    if (at == Along::First) return (above - centre) * invh;
    if (at == Along::Last) return (centre - below) * invh;
    return (above - below) * inv2h;
  }
};
struct Smooth {
  double operator()(double below, double centre, double above, Along at) const {
    if (at == Along::First) return (2.0 / 3) * centre + (1.0 / 3) * above;
    if (at == Along::Last) return (2.0 / 3) * centre + (1.0 / 3) * below;
    return (2.0 / 3) * centre + (1.0 / 6) * (above + below);
  }
};

inline Along along(int p, int count) { return p == 0 ? Along::First : (p == count - 1 ? Along::Last : Along::Inner); }

// dst = op along x (axis 0) or y (axis 1) of src within a plane.
template <typename Op>
void inPlane(const GridSpec& g, const double* src, double* dst, int axis, const Op& op) {
  const std::size_t stride = axis == 0 ? 1 : std::size_t(g.dims.i);
  const int count = axis == 0 ? g.dims.i : g.dims.j;
  for (int j = 0; j < g.dims.j; ++j)
    for (int i = 0; i < g.dims.i; ++i) {
      const std::size_t m = std::size_t(i) + std::size_t(g.dims.i) * std::size_t(j);
      const Along at = along(axis == 0 ? i : j, count);
      dst[m] = op(at == Along::First ? 0.0 : src[m - stride], src[m], at == Along::Last ? 0.0 : src[m + stride], at);
    }
}

// dst = op along z at plane k, from planes k - 1 (below), k (centre) and
// k + 1 (above); below / above are not read at the walls.
template <typename Op>
void acrossPlanes(const GridSpec& g, const double* below, const double* centre, const double* above, int k,
                  double* dst, const Op& op) {
  const std::size_t plane = std::size_t(g.dims.i) * std::size_t(g.dims.j);
  const Along at = along(k, g.dims.k);
  for (std::size_t m = 0; m < plane; ++m)
    dst[m] = op(at == Along::First ? 0.0 : below[m], centre[m], at == Along::Last ? 0.0 : above[m], at);
}

// Planes per thread: two windows of three (x: the y-smoothed x difference;
// y: the y difference), two temporaries and the three components.
constexpr std::size_t kPlanesPerThread = 11;

// fn(k, gx, gy, gz) for every z plane k, with the planes of the projected
// gradient's components (1/m times the unit of phi); planes in parallel
// chunks. The per-thread planes live in scratch.scalar0.
template <typename Fn>
void forEachGradientPlane(GridView<const double> phi, GridScratch& scratch, const Fn& fn) {
  const GridSpec& g = phi.spec;
  const std::size_t plane = std::size_t(g.dims.i) * std::size_t(g.dims.j);
  const int nz = g.dims.k;
  const auto phiPlane = [&](int k) { return phi.data + std::size_t(k) * plane; };
  const Difference difference(g.dx);
  const Smooth smooth;
  forEachPlaneChunk(nz, plane, kPlanesPerThread, scratch.scalar0, [&](int first, int end, double* base) {
    // x: the difference along x smoothed along y; y: the difference along y.
    PlaneWindow<double> xWindow(base, plane, first, nz), yWindow(base + 3 * plane, plane, first, nz);
    double* t0 = base + 6 * plane;
    double* t1 = base + 7 * plane;
    double* gx = base + 8 * plane;
    double* gy = base + 9 * plane;
    double* gz = base + 10 * plane;
    for (int k = first; k != end; ++k) {
      xWindow.advanceTo(k, [&](int j, double* dst) {
        inPlane(g, phiPlane(j), t0, 0, difference);
        inPlane(g, t0, dst, 1, smooth);
      });
      yWindow.advanceTo(k, [&](int j, double* dst) { inPlane(g, phiPlane(j), dst, 1, difference); });
      // x: difference along x, smoothed along y (the window), then along z.
      acrossPlanes(g, xWindow.at(k - 1), xWindow.at(k), xWindow.at(k + 1), k, gx, smooth);
      // y: difference along y (the window), smoothed along z, then along x.
      acrossPlanes(g, yWindow.at(k - 1), yWindow.at(k), yWindow.at(k + 1), k, t0, smooth);
      inPlane(g, t0, gy, 0, smooth);
      // z: difference along z, smoothed along x, then along y.
      acrossPlanes(g, k > 0 ? phiPlane(k - 1) : nullptr, phiPlane(k), k + 1 < nz ? phiPlane(k + 1) : nullptr, k, t0,
                   difference);
      inPlane(g, t0, t1, 0, smooth);
      inPlane(g, t1, gz, 1, smooth);
      fn(k, static_cast<const double*>(gx), static_cast<const double*>(gy), static_cast<const double*>(gz));
    }
  });
}

}  // namespace

void projectedGradient(GridView<const double> phi, GridView<Vec3d> gradient, GridScratch* scratch) {
  require(phi.spec == gradient.spec, "projectedGradient: grids differ");
  GridScratch local;
  GridScratch& s = scratch ? *scratch : local;
  const std::size_t plane = std::size_t(phi.spec.dims.i) * std::size_t(phi.spec.dims.j);
  forEachGradientPlane(phi, s, [&](int k, const double* gx, const double* gy, const double* gz) {
    Vec3d* out = gradient.data + std::size_t(k) * plane;
    for (std::size_t q = 0; q < plane; ++q) out[q] = {gx[q], gy[q], gz[q]};
  });
}

void recoverNodalFields(GridView<const double> phi, GridView<const Vec3d> Hext, GridView<const double> n,
                        const MagnetizationLaw<double>& law, GridView<Vec3d> H, GridView<Vec3d> M,
                        GridView<Vec3d> B, GridScratch* scratch) {
  const GridSpec& g = phi.spec;
  require(Hext.spec == g && n.spec == g, "recoverNodalFields: input grids differ");
  GridScratch local;
  GridScratch& s = scratch ? *scratch : local;
  const std::size_t plane = std::size_t(g.dims.i) * std::size_t(g.dims.j);
  forEachGradientPlane(phi, s, [&](int k, const double* gx, const double* gy, const double* gz) {
    const std::size_t first = std::size_t(k) * plane;
    for (std::size_t q = 0; q < plane; ++q) {
      const std::size_t m = first + q;
      const Vec3d h = Hext[m] - Vec3d{gx[q], gy[q], gz[q]};
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
