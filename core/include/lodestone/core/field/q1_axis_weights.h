#pragma once
// The vacuum stiffness K = dx (k x m x m + m x k x m + m x m x k) of
// q1_stencil.h, row by row from its 1D factors: stiffness k = [-1 2 -1] and
// mass m = [1/6 4/6 1/6], each halved at a wall. Host and device (the CUDA
// backend's kernels call the same functions).
#include <cstddef>

#include "lodestone/core/base/hostdev.h"

namespace lodestone {
inline namespace field {
namespace q1 {

/// The 1D factors of node p of an axis of `count` nodes (offsets -1, 0, +1).
struct AxisWeights {
  double k[3], m[3];
};

LODESTONE_HOSTDEV inline AxisWeights axisWeights(int p, int count) {
  const bool left = p > 0, right = p < count - 1;
  const double cells = double(left) + double(right);
  AxisWeights a;
  a.k[0] = left ? -1.0 : 0.0;
  a.k[1] = cells;
  a.k[2] = right ? -1.0 : 0.0;
  a.m[0] = left ? 1.0 / 6 : 0.0;
  a.m[1] = cells * (2.0 / 6);
  a.m[2] = right ? 1.0 / 6 : 0.0;
  return a;
}

/// Diagonal of K at node (i,j,k) of an nx x ny x nz grid of spacing dx (m).
LODESTONE_HOSTDEV inline double laplacianDiagonal(int nx, int ny, int nz, double dx, int i, int j, int k) {
  const AxisWeights x = axisWeights(i, nx), y = axisWeights(j, ny), z = axisWeights(k, nz);
  return dx * (x.k[1] * y.m[1] * z.m[1] + x.m[1] * y.k[1] * z.m[1] + x.m[1] * y.m[1] * z.k[1]);
}

/// Row (i,j,k) of K times v (node index i + nx (j + ny k)), for any node,
/// walls included; summed in double.
template <typename T>
LODESTONE_HOSTDEV inline double laplacianRow(int nx, int ny, int nz, double dx, int i, int j, int k, const T* v) {
  const AxisWeights x = axisWeights(i, nx), y = axisWeights(j, ny), z = axisWeights(k, nz);
  double s = 0;
  for (int c = -1; c <= 1; ++c) {
    if (z.m[c + 1] == 0) continue;
    for (int b = -1; b <= 1; ++b) {
      if (y.m[b + 1] == 0) continue;
      for (int a = -1; a <= 1; ++a) {
        if (x.m[a + 1] == 0) continue;
        const double w = x.k[a + 1] * y.m[b + 1] * z.m[c + 1] + x.m[a + 1] * y.k[b + 1] * z.m[c + 1] +
                         x.m[a + 1] * y.m[b + 1] * z.k[c + 1];
        const std::size_t node =
            std::size_t(i + a) + std::size_t(nx) * (std::size_t(j + b) + std::size_t(ny) * std::size_t(k + c));
        s += w * double(v[node]);
      }
    }
  }
  return dx * s;
}

}  // namespace q1
}  // namespace field
}  // namespace lodestone
