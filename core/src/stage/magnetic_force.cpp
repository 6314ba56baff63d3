#include "lodestone/core/stage/magnetic_force.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/kept_capacity.h"
#include "lodestone/core/base/parallel.h"
#include "lodestone/core/sources/field_source.h"
#include "plane_sweep.h"

namespace lodestone {
inline namespace stage {

const char* toString(ForceMask mask) {
  switch (mask) {
    case ForceMask::Material: return "material";
    case ForceMask::None: return "none";
  }
  return "unknown";
}

Vec3d appliedFieldForceDensity(const FieldSource& source, const Vec3d& x, const Vec3d& M, double dx, double time) {
  // (M . grad) H_s as the directional derivative along M over +-h, h = 1e-3
  // dx, of the field the material sees (the source's field, continued
  // through a magnet's faces inside it: continuous across them, so a node on
  // a face does not take in the jump of H_s, which gave a force ~1/h too
  // large): exact up to O(h^2 H'''). Where the continuation itself changes
  // between the two points (a node within h of a face, or of the surface
  // inside a magnet where the nearest face changes), the derivative is taken
  // one-sided, second order, from the side of the smaller continuation.
  const double Mn = norm(M);
  if (!(Mn > 0)) return {};
  const double h = 1e-3 * dx;
  const Vec3d d = (h / Mn) * M;
  const auto seen = [&](const Vec3d& y) { return source.field(y, time) + source.exteriorContinuation(y, time); };
  const Vec3d cUp = source.exteriorContinuation(x + d, time), cDn = source.exteriorContinuation(x - d, time);
  Vec3d dH;  // derivative along M / |M|, A/m^2
  if (cUp == cDn) {  // the continuation cancels
    dH = (source.field(x + d, time) - source.field(x - d, time)) / (2 * h);
  } else {
    const double side = norm2(cUp) < norm2(cDn) ? 1.0 : -1.0;
    const Vec3d e = side * d;
    dH = (-side / h) * (2.5 * seen(x + e) - 4.0 * seen(x + 2.0 * e) + 1.5 * seen(x + 3.0 * e));
  }
  return (kMu0 * Mn) * dH;
}

MagnetWrench sourceReaction(GridView<const Vec3d> materialM, const FieldSource& source, const Vec3d& centre,
                            double time) {
  require(std::isfinite(time), "sourceReaction: time must be finite, got ", time, " s");
  struct Sum {
    Vec3d force, torque;
    Sum& operator+=(const Sum& o) {
      force += o.force;
      torque += o.torque;
      return *this;
    }
  };
  const GridSpec& g = materialM.spec;
  const double cell = g.cellVolume();
  const std::size_t plane = std::size_t(g.dims.i) * std::size_t(g.dims.j);
  const Sum sum = deterministicSum<Sum>(g.nodeCount(), [&](std::size_t m) {
    Sum w;
    const Vec3d& M = materialM[m];
    if (M == Vec3d{}) return w;
    const int k = int(m / plane), j = int((m % plane) / std::size_t(g.dims.i)), i = int(m % std::size_t(g.dims.i));
    const Vec3d x = g.nodePosition(i, j, k);
    const Vec3d f = cell * appliedFieldForceDensity(source, x, M, g.dx, time);
    const Vec3d Hs = source.field(x, time) + source.exteriorContinuation(x, time);
    w.force = -1.0 * f;
    w.torque = -1.0 * (cross(x - centre, f) + (kMu0 * cell) * cross(M, Hs));
    return w;
  });
  return {sum.force, sum.torque};
}

namespace {

// Nodes within `dilation` nodes (per axis) of material, n above
// kMaskDustFraction of its maximum (particles on B-spline tie points, a
// weight 0 in exact arithmetic, leave round-off dust of 1e-30 and less of the
// maximum on one side only, which would break the mask's symmetry and give a
// symmetric body a net force): 1, else 0, in scratch.mask0 or mask1. The box
// dilation is three one-axis passes, each an OR of shifted copies: of a row
// (x), of a plane's rows (y), of neighbouring planes (z).
const std::uint8_t* materialMask(GridView<const double> n, int dilation, GridScratch& scratch) {
  const GridSpec& g = n.spec;
  const std::size_t count = g.nodeCount(), nx = std::size_t(g.dims.i);
  const double nMax = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, count, std::size_t(1) << 14), 0.0,
      [&](const tbb::blocked_range<std::size_t>& r, double acc) {
        for (std::size_t m = r.begin(); m != r.end(); ++m) acc = std::max(acc, n[m]);
        return acc;
      },
      [](double a, double b) { return std::max(a, b); });
  const double threshold = kMaskDustFraction * nMax;
  std::vector<std::uint8_t>&a = scratch.mask0, &b = scratch.mask1;
  resizeKeepingCapacity(a, count);  // every value is written before it is read
  resizeKeepingCapacity(b, count);
  const auto rows = [&](const auto& rowFn) {
    tbb::parallel_for(0, g.dims.k, [&](int k) {
      for (int j = 0; j < g.dims.j; ++j) rowFn(j, k, g.index(0, j, k));
    });
  };
  // Byte stores may alias anything, so every loop works through local
  // pointers marked as not aliasing (the compiler then vectorizes it).
  rows([&](int, int, std::size_t row) {
    std::uint8_t* __restrict out = a.data() + row;
    const double* __restrict in = n.data + row;
    for (std::size_t i = 0; i < nx; ++i) out[i] = in[i] > threshold;
  });
  if (dilation == 0) return a.data();
  // x: b[i] = OR of a[i + s], |s| <= dilation, within the row.
  rows([&](int, int, std::size_t row) {
    const std::uint8_t* __restrict src = a.data() + row;
    std::uint8_t* __restrict dst = b.data() + row;
    std::fill(dst, dst + nx, std::uint8_t(0));
    for (int s = -dilation; s <= dilation; ++s) {
      const std::size_t from = std::size_t(std::max(0, -s)), to = nx - std::size_t(std::max(0, s));
      for (std::size_t i = from; i < to; ++i) dst[i] |= src[std::ptrdiff_t(i) + s];
    }
  });
  // y, then z, a plane at a time: the OR of the plane's rows shifted by
  // up to `dilation` rows (y), or of the planes within `dilation` (z).
  const std::size_t plane = nx * std::size_t(g.dims.j);
  for (int axis = 1; axis < 3; ++axis) {
    const std::uint8_t* src = (axis == 1 ? b : a).data();
    std::uint8_t* dst = (axis == 1 ? a : b).data();
    tbb::parallel_for(0, g.dims.k, [&](int k) {
      std::uint8_t* __restrict out = dst + std::size_t(k) * plane;
      std::fill(out, out + plane, std::uint8_t(0));
      if (axis == 1) {
        const std::uint8_t* __restrict in = src + std::size_t(k) * plane;
        for (int s = -dilation; s <= dilation; ++s) {
          const std::size_t from = nx * std::size_t(std::max(0, -s)),
                            to = plane - nx * std::size_t(std::max(0, s));
          const std::ptrdiff_t shift = std::ptrdiff_t(nx) * s;
          for (std::size_t m = from; m < to; ++m) out[m] |= in[std::ptrdiff_t(m) + shift];
        }
      } else {
        for (int q = std::max(k - dilation, 0); q <= std::min(k + dilation, g.dims.k - 1); ++q) {
          const std::uint8_t* __restrict in = src + std::size_t(q) * plane;
          for (std::size_t m = 0; m < plane; ++m) out[m] |= in[m];
        }
      }
    });
  }
  return b.data();
}

}  // namespace

void stressDivergence(GridView<const Vec3d> H, GridView<const Vec3d> B, GridView<const Vec3d> Hext,
                      GridView<const double> n, ForceMask mask, GridView<Vec3d> t, int dilation,
                      const FieldSource* applied, double time, GridScratch* scratch) {
  require(std::isfinite(time), "stressDivergence: time must be finite, got ", time, " s");
  require(dilation >= 0 && dilation <= 8, "stressDivergence: mask dilation must be 0..8 nodes, got ", dilation);
  const GridSpec& g = H.spec;
  require(B.spec == g && t.spec == g && Hext.spec == g, "stressDivergence: grids differ");
  require(mask == ForceMask::None || (n.data && n.spec == g), "stressDivergence: the material mask needs n");
  const int dims[3] = {g.dims.i, g.dims.j, g.dims.k};
  const std::ptrdiff_t stride[3] = {1, std::ptrdiff_t(g.dims.i), std::ptrdiff_t(g.dims.i) * g.dims.j};
  // Row a of the self stress at node m: B_d,a H_d - (mu0/2)|H_d|^2 e_a with
  // H_d = H - H_ext and B_d = B - mu0 H_ext = mu0 (H_d + M).
  const auto row = [&](std::size_t m, int a) {
    const Vec3d Hd = H[m] - Hext[m];
    Vec3d r = (B[m][a] - kMu0 * Hext[m][a]) * Hd;
    r[a] -= 0.5 * kMu0 * norm2(Hd);
    return r;
  };
  // The material mask: nodes within `dilation` nodes (per axis) of n > 0.
  GridScratch local;
  GridScratch& sc = scratch ? *scratch : local;
  const std::uint8_t* near = mask == ForceMask::Material ? materialMask(n, dilation, sc) : nullptr;
  tbb::parallel_for(0, g.dims.k, [&](int k) {
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        const std::size_t m = g.index(i, j, k);
        if (near && !near[m]) {
          t[m] = Vec3d{};
          continue;
        }
        const int p[3] = {i, j, k};
        // div T_self + mu0 (M . grad) H_ext, with M = B/mu0 - H.
        const Vec3d M = B[m] / kMu0 - H[m];
        Vec3d div{};
        for (int a = 0; a < 3; ++a) {
          const std::size_t up = p[a] < dims[a] - 1 ? m + std::size_t(stride[a]) : m;
          const std::size_t dn = p[a] > 0 ? m - std::size_t(stride[a]) : m;
          const double span = g.dx * double((up != m) + (dn != m));
          div += (row(up, a) - row(dn, a)) / span;
          if (!applied) div += (kMu0 * M[a] / span) * (Hext[up] - Hext[dn]);
        }
        if (applied) div += appliedFieldForceDensity(*applied, g.nodePosition(i, j, k), M, g.dx, time);
        t[m] = div;
      }
  });
}

void spreadForce(GridView<const Vec3d> t, GridView<Vec3d> f, GridScratch* scratch) {
  const GridSpec& g = t.spec;
  require(f.spec == g, "spreadForce: grids differ");
  const std::size_t count = g.nodeCount();
  GridScratch local;
  GridScratch& sc = scratch ? *scratch : local;
  // The three one-axis passes (x, y, then z) z plane by z plane: x and y
  // within a plane, z from a window of the three xy-spread planes around it;
  // each value by the same operations in the same order as whole-grid passes.
  // Chunks of planes run in parallel; t is first copied when it is f itself
  // (a chunk reads the planes next to its own, which another chunk writes).
  const Vec3d* src = t.data;
  if (t.data == f.data) {
    sc.vector0.resize(count);
    std::copy(t.data, t.data + count, sc.vector0.data());
    src = sc.vector0.data();
  }
  const int nx = g.dims.i, ny = g.dims.j, nz = g.dims.k;
  const std::size_t plane = std::size_t(nx) * std::size_t(ny);
  const double r0 = 2.0 * g.dx / 3.0, r1 = g.dx / 6.0;
  constexpr std::size_t kPlanes = 4;  // per thread: a window of three xy-spread planes and one temporary
  // out = the spread of in along one in-plane axis (stride 1: x; nx: y).
  const auto spreadInPlane = [&](const Vec3d* in, Vec3d* out, int axis) {
    const std::size_t stride = axis == 0 ? 1 : std::size_t(nx);
    const int extent = axis == 0 ? nx : ny;
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::size_t m = std::size_t(i) + std::size_t(nx) * std::size_t(j);
        const int p = axis == 0 ? i : j;
        Vec3d v = r0 * in[m];
        if (p > 0) v += r1 * in[m - stride];
        if (p < extent - 1) v += r1 * in[m + stride];
        out[m] = v;
      }
  };
  forEachPlaneChunk(nz, plane, kPlanes, sc.vector1, [&](int first, int end, Vec3d* base) {
    PlaneWindow<Vec3d> window(base, plane, first, nz);  // the xy-spread planes
    Vec3d* temp = base + 3 * plane;
    for (int k = first; k != end; ++k) {
      window.advanceTo(k, [&](int j, Vec3d* dst) {
        spreadInPlane(src + std::size_t(j) * plane, temp, 0);
        spreadInPlane(temp, dst, 1);
      });
      const Vec3d* centre = window.at(k);
      const Vec3d* below = window.at(k - 1);
      const Vec3d* above = window.at(k + 1);
      Vec3d* out = f.data + std::size_t(k) * plane;
      for (std::size_t q = 0; q < plane; ++q) {
        Vec3d v = r0 * centre[q];
        if (below) v += r1 * below[q];
        if (above) v += r1 * above[q];
        out[q] = v;
      }
    }
  });
}

Vec3d gatherToSupport(GridView<const Vec3d> f, GridView<const double> n, GridView<Vec3d> out, int maxDistance) {
  const GridSpec& g = f.spec;
  require(n.spec == g && out.spec == g, "gatherToSupport: grids differ");
  require(maxDistance >= 0 && maxDistance <= 16, "gatherToSupport: maxDistance must be 0..16 nodes, got ", maxDistance);
  const std::size_t count = g.nodeCount();
  constexpr int kFar = 1 << 20;
  // Only the box of the support (n > 0) grown by maxDistance can hold a node
  // within reach; every node outside it is farther (kFar). The passes run
  // over that box alone (the material is usually a small part of the grid).
  struct Box {
    int lo[3] = {1 << 30, 1 << 30, 1 << 30}, hi[3] = {-1, -1, -1};
    void add(const Box& o) {
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], o.lo[a]);
        hi[a] = std::max(hi[a], o.hi[a]);
      }
    }
  };
  const Box support = tbb::parallel_reduce(
      tbb::blocked_range<int>(0, g.dims.k), Box{},
      [&](const tbb::blocked_range<int>& r, Box b) {
        for (int k = r.begin(); k != r.end(); ++k)
          for (int j = 0; j < g.dims.j; ++j)
            for (int i = 0; i < g.dims.i; ++i)
              if (n[g.index(i, j, k)] > 0) {
                const int c[3] = {i, j, k};
                for (int a = 0; a < 3; ++a) {
                  b.lo[a] = std::min(b.lo[a], c[a]);
                  b.hi[a] = std::max(b.hi[a], c[a]);
                }
              }
        return b;
      },
      [](Box a, const Box& b) {
        a.add(b);
        return a;
      });
  if (support.hi[0] < 0) {  // no support: everything is dropped
    Vec3d lost{};
    for (std::size_t m = 0; m < count; ++m) lost += f[m];
    std::fill(out.data, out.data + count, Vec3d{});
    return lost;
  }
  int lo[3], dims[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(support.lo[a] - maxDistance, 0);
    dims[a] = std::min(support.hi[a] + maxDistance, g.dims[a] - 1) - lo[a] + 1;
  }
  const std::size_t boxCount = std::size_t(dims[0]) * std::size_t(dims[1]) * std::size_t(dims[2]);
  const auto local = [&](int i, int j, int k) {
    return std::size_t(i) + std::size_t(dims[0]) * (std::size_t(j) + std::size_t(dims[1]) * std::size_t(k));
  };
  const auto global = [&](int i, int j, int k) { return g.index(i + lo[0], j + lo[1], k + lo[2]); };
  const auto forBox = [&](const auto& fn) {  // fn(i, j, k) in box coordinates, z-slabs in parallel
    tbb::parallel_for(0, dims[2], [&](int k) {
      for (int j = 0; j < dims[1]; ++j)
        for (int i = 0; i < dims[0]; ++i) fn(i, j, k);
    });
  };
  // d: node distance (26-connectivity) to the support, up to maxDistance
  // (kFar beyond): the max-norm of the node steps, which within the box is
  // the 26-connected path length. Separable: one pass per axis,
  // d(x) = min_t max(|t|, d(x + t e_axis)), |t| <= maxDistance.
  std::vector<int> d(boxCount, kFar);
  forBox([&](int i, int j, int k) { d[local(i, j, k)] = n[global(i, j, k)] > 0 ? 0 : kFar; });
  const std::size_t stride[3] = {1, std::size_t(dims[0]), std::size_t(dims[0]) * std::size_t(dims[1])};
  for (int a = 0; a < 3; ++a) {
    const int len = dims[a], lines = dims[(a + 1) % 3], slabs = dims[(a + 2) % 3];
    const std::size_t along = stride[a], across = stride[(a + 1) % 3], slab = stride[(a + 2) % 3];
    tbb::parallel_for(0, slabs, [&d, len, lines, along, across, slab, maxDistance](int ic) {
      std::vector<int> line(static_cast<std::size_t>(len));
      for (int ib = 0; ib < lines; ++ib) {
        const std::size_t base = std::size_t(ib) * across + std::size_t(ic) * slab;
        for (int x = 0; x < len; ++x) line[std::size_t(x)] = d[base + std::size_t(x) * along];
        for (int x = 0; x < len; ++x) {
          int best = line[std::size_t(x)];
          for (int t = 1; t <= maxDistance && t < best; ++t) {
            if (x - t >= 0) best = std::min(best, std::max(t, line[std::size_t(x - t)]));
            if (x + t < len) best = std::min(best, std::max(t, line[std::size_t(x + t)]));
          }
          d[base + std::size_t(x) * along] = best;
        }
      }
    });
  }
  const auto forNeighbours = [&](int i, int j, int k, const auto& fn) {
    for (int c = std::max(k - 1, 0); c <= std::min(k + 1, dims[2] - 1); ++c)
      for (int b = std::max(j - 1, 0); b <= std::min(j + 1, dims[1] - 1); ++b)
        for (int a = std::max(i - 1, 0); a <= std::min(i + 1, dims[0] - 1); ++a)
          if (a != i || b != j || c != k) fn(local(a, b, c));
  };
  // Each node at distance L > 0 splits what it holds equally among its
  // neighbours at distance L - 1, outermost level first.
  std::vector<Vec3d> acc(boxCount);
  std::vector<int> inward(boxCount, 0);
  forBox([&](int i, int j, int k) {
    const std::size_t m = local(i, j, k);
    acc[m] = f[global(i, j, k)];
    if (d[m] == 0 || d[m] == kFar) return;
    int c = 0;
    forNeighbours(i, j, k, [&](std::size_t o) { c += d[o] == d[m] - 1; });
    inward[m] = c;
  });
  for (int level = maxDistance - 1; level >= 0; --level) {
    forBox([&](int i, int j, int k) {
      const std::size_t m = local(i, j, k);
      if (d[m] != level) return;
      Vec3d pulled{};
      forNeighbours(i, j, k, [&](std::size_t o) {
        if (d[o] == level + 1) pulled += acc[o] / double(inward[o]);
      });
      acc[m] += pulled;
    });
  }
  // Out of reach (outside the box, or in it beyond maxDistance): dropped,
  // summed in index order.
  Vec3d lost{};
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j) {
      const bool rowInBox = k >= lo[2] && k < lo[2] + dims[2] && j >= lo[1] && j < lo[1] + dims[1];
      const std::size_t row = g.index(0, j, k);
      for (int i = 0; i < g.dims.i; ++i) {
        const bool inBox = rowInBox && i >= lo[0] && i < lo[0] + dims[0];
        const int dm = inBox ? d[local(i - lo[0], j - lo[1], k - lo[2])] : kFar;
        if (dm == 0) {
          out[row + std::size_t(i)] = acc[local(i - lo[0], j - lo[1], k - lo[2])];
        } else {
          if (dm == kFar) lost += f[row + std::size_t(i)];
          out[row + std::size_t(i)] = Vec3d{};
        }
      }
    }
  return lost;
}

}  // namespace stage
}  // namespace lodestone
