#pragma once
// The vacuum part of the field operator: the trilinear-element stiffness of
// the Laplacian on a node grid,
//   K = dx (k x m x m + m x k x m + m x m x k),
// 1D stiffness k = [-1 2 -1] and lumped-free 1D mass m = [1/6 4/6 1/6]
// (halved at the walls). Interior rows: centre 8/3, faces 0, edges -1/6,
// corners -1/12 (times dx); rows sum to zero.
#include "lodestone/core/field/boundary_kind.h"
#include "lodestone/core/base/grid.h"

namespace lodestone {
inline namespace field {

/// out = K v on free rows (all rows for Shield; interior rows for Open, whose
/// wall rows are set to 0). Values of v on wall nodes enter the rows next to them.
void applyQ1Laplacian(const GridSpec& grid, BoundaryKind boundary, const double* v, double* out);
/// The same in single precision (the multigrid preconditioner's storage).
void applyQ1Laplacian(const GridSpec& grid, BoundaryKind boundary, const float* v, float* out);

/// applyQ1Laplacian on the node row (j, k) alone (out at that row's nodes),
/// for callers that fuse more work into the same pass over the rows.
void applyQ1LaplacianRow(const GridSpec& grid, BoundaryKind boundary, int j, int k, const double* v, double* out);

/// Row (i,j,k) of K times v, for any node including the walls.
double q1LaplacianRow(const GridSpec& grid, int i, int j, int k, const double* v);
/// The same for single-precision v (summed in double).
double q1LaplacianRow(const GridSpec& grid, int i, int j, int k, const float* v);

/// Diagonal entry of K at node (i,j,k).
double q1LaplacianDiagonal(const GridSpec& grid, int i, int j, int k);

/// diag(K) at every node.
void q1LaplacianDiagonalAll(const GridSpec& grid, double* out);

/// Sets the fixed (wall) nodes of v to 0 for Open; nothing for Shield.
void zeroFixedNodes(const GridSpec& grid, BoundaryKind boundary, double* v);
void zeroFixedNodes(const GridSpec& grid, BoundaryKind boundary, float* v);

/// Sets the fixed (wall) nodes of v to `value` for Open; nothing for Shield.
void setFixedNodes(const GridSpec& grid, BoundaryKind boundary, double value, double* v);
void setFixedNodes(const GridSpec& grid, BoundaryKind boundary, float value, float* v);

}  // namespace field
}  // namespace lodestone
