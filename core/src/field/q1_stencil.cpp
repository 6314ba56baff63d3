#include "lodestone/core/field/q1_stencil.h"

#include "lodestone/core/field/q1_axis_weights.h"

#include <algorithm>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace lodestone {
inline namespace field {

const char* toString(BoundaryKind kind) {
  switch (kind) {
    case BoundaryKind::Open: return "open";
    case BoundaryKind::Shield: return "shield";
  }
  return "unknown";
}

// ---------------------------------------------------------------------------
// Vacuum Laplacian: the Q1 stiffness K = dx (k x m x m + m x k x m + m x m x k)
// with 1D stiffness k = [-1 2 -1] and mass m = [1/6 4/6 1/6] (halved at walls).
// Interior rows: centre 8/3, face 0, edge -1/6, corner -1/12 (times dx).

double q1LaplacianDiagonal(const GridSpec& grid, int i, int j, int k) {
  return q1::laplacianDiagonal(grid.dims.i, grid.dims.j, grid.dims.k, grid.dx, i, j, k);
}

template <typename T>
double q1LaplacianRowT(const GridSpec& grid, int i, int j, int k, const T* v) {
  return q1::laplacianRow(grid.dims.i, grid.dims.j, grid.dims.k, grid.dx, i, j, k, v);
}

double q1LaplacianRow(const GridSpec& grid, int i, int j, int k, const double* v) {
  return q1LaplacianRowT(grid, i, j, k, v);
}
double q1LaplacianRow(const GridSpec& grid, int i, int j, int k, const float* v) {
  return q1LaplacianRowT(grid, i, j, k, v);
}

template <typename T>
void applyQ1LaplacianRowT(const GridSpec& grid, BoundaryKind boundary, int j, int k, const T* v, T* out) {
  const int nx = grid.dims.i, ny = grid.dims.j, nz = grid.dims.k;
  const std::ptrdiff_t sy = nx, sz = std::ptrdiff_t(nx) * ny;
  const T h = T(grid.dx), cC = h * T(8.0 / 3.0), cE = -h / T(6), cK = -h / T(12);
  const bool shield = boundary == BoundaryKind::Shield;
  const std::size_t row = grid.index(0, j, k);
  const bool wallRow = k == 0 || k == nz - 1 || j == 0 || j == ny - 1;
  if (wallRow) {
    for (int i = 0; i < nx; ++i) out[row + std::size_t(i)] = shield ? T(q1LaplacianRowT(grid, i, j, k, v)) : T(0);
    return;
  }
  out[row] = shield ? T(q1LaplacianRowT(grid, 0, j, k, v)) : T(0);
  out[row + std::size_t(nx - 1)] = shield ? T(q1LaplacianRowT(grid, nx - 1, j, k, v)) : T(0);
  // Per x position, the 4 in-plane face neighbours A and the 4 in-plane
  // diagonal neighbours D in (y, z); then edges(i) = A(i-1) + A(i+1) + D(i)
  // and corners(i) = D(i-1) + D(i+1). Face neighbours weigh 0.
  const T* p = v + row;
  thread_local std::vector<T> A, D;
  A.resize(std::size_t(nx));
  D.resize(std::size_t(nx));
  for (int i = 0; i < nx; ++i) {
    const T* c = p + i;
    A[std::size_t(i)] = c[sy] + c[-sy] + c[sz] + c[-sz];
    D[std::size_t(i)] = c[sy + sz] + c[sy - sz] + c[-sy + sz] + c[-sy - sz];
  }
  for (int i = 1; i < nx - 1; ++i) {
    const std::size_t u = std::size_t(i);
    const T edges = A[u - 1] + A[u + 1] + D[u];
    const T corners = D[u - 1] + D[u + 1];
    out[row + u] = cC * p[i] + cE * edges + cK * corners;
  }
}

namespace {
template <typename T>
void applyQ1LaplacianT(const GridSpec& grid, BoundaryKind boundary, const T* v, T* out) {
  tbb::parallel_for(tbb::blocked_range<int>(0, grid.dims.k, 1), [&](const tbb::blocked_range<int>& kr) {
    for (int k = kr.begin(); k != kr.end(); ++k)
      for (int j = 0; j < grid.dims.j; ++j) applyQ1LaplacianRowT(grid, boundary, j, k, v, out);
  });
}
}  // namespace

void applyQ1LaplacianRow(const GridSpec& grid, BoundaryKind boundary, int j, int k, const double* v, double* out) {
  applyQ1LaplacianRowT(grid, boundary, j, k, v, out);
}

void applyQ1Laplacian(const GridSpec& grid, BoundaryKind boundary, const double* v, double* out) {
  applyQ1LaplacianT(grid, boundary, v, out);
}
void applyQ1Laplacian(const GridSpec& grid, BoundaryKind boundary, const float* v, float* out) {
  applyQ1LaplacianT(grid, boundary, v, out);
}

void zeroFixedNodes(const GridSpec& grid, BoundaryKind boundary, double* v) {
  setFixedNodes(grid, boundary, 0.0, v);
}
void zeroFixedNodes(const GridSpec& grid, BoundaryKind boundary, float* v) {
  setFixedNodes(grid, boundary, 0.0f, v);
}

void q1LaplacianDiagonalAll(const GridSpec& grid, double* out) {
  const double interior = grid.dx * 8.0 / 3.0;
  tbb::parallel_for(0, grid.dims.k, [&](int k) {
    for (int j = 0; j < grid.dims.j; ++j) {
      const bool wallRow = k == 0 || k == grid.dims.k - 1 || j == 0 || j == grid.dims.j - 1;
      double* row = out + grid.index(0, j, k);
      for (int i = 0; i < grid.dims.i; ++i)
        row[i] = (wallRow || i == 0 || i == grid.dims.i - 1) ? q1LaplacianDiagonal(grid, i, j, k) : interior;
    }
  });
}

namespace {
template <typename T>
void setFixedNodesT(const GridSpec& grid, BoundaryKind boundary, T value, T* v) {
  if (boundary == BoundaryKind::Shield) return;
  const int nx = grid.dims.i, ny = grid.dims.j, nz = grid.dims.k;
  tbb::parallel_for(0, nz, [&](int k) {
    for (int j = 0; j < ny; ++j) {
      const std::size_t row = grid.index(0, j, k);
      if (k == 0 || k == nz - 1 || j == 0 || j == ny - 1) {
        std::fill(v + row, v + row + std::size_t(nx), value);
      } else {
        v[row] = value;
        v[row + std::size_t(nx - 1)] = value;
      }
    }
  });
}
}  // namespace

void setFixedNodes(const GridSpec& grid, BoundaryKind boundary, double value, double* v) {
  setFixedNodesT(grid, boundary, value, v);
}
void setFixedNodes(const GridSpec& grid, BoundaryKind boundary, float value, float* v) {
  setFixedNodesT(grid, boundary, value, v);
}

}  // namespace field
}  // namespace lodestone
