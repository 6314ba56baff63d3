#pragma once
// Nodal fields recovered from the potential of a field solve:
//   H_i = H_ext,i - (grad phi)_i,  M_i = M(H_i; n_i),  B_i = mu0 (H_i + M_i).
// (grad phi)_i is the lumped-L2 projection of the trilinear gradient onto the
// nodes: a central difference along the component's axis smoothed by
// [1/6, 2/3, 1/6] across it (one-sided, [2/3, 1/3], at the walls). It is
// exact for linear phi and second-order accurate inside. (Like any nodal
// average of the element gradient it cannot see a pure 3D checkerboard; phi
// never carries one because the element energy penalizes it, see
// test_fe_operator.)
#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/grid_scratch.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace stage {

/// grad(phi) at every node, 1/m times the unit of phi. `scratch`, when
/// given, holds the temporaries (a few z planes per thread) between calls
/// (results are the same).
void projectedGradient(GridView<const double> phi, GridView<Vec3d> gradient, GridScratch* scratch = nullptr);

/// H (A/m), M (A/m) and B (T) at every node; any output view may be empty
/// (data == nullptr) to skip it. Hext: applied field at the nodes (A/m);
/// n: micro-particle density (1/m^3). `scratch` as for projectedGradient.
void recoverNodalFields(GridView<const double> phi, GridView<const Vec3d> Hext, GridView<const double> n,
                        const MagnetizationLaw<double>& law, GridView<Vec3d> H, GridView<Vec3d> M,
                        GridView<Vec3d> B, GridScratch* scratch = nullptr);

}  // namespace stage
}  // namespace lodestone
