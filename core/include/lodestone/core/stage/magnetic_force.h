#pragma once
// Magnetic force on the grid (Section 4.2 of the paper, docs/physics.md):
// the Einstein-Laub stress T = B (x) H - (mu0/2)|H|^2 I at the nodes, its
// divergence by central differences (Eq. 32) contracted over B's index,
// and the spread f_i = sum_j R_ij t_j with R_ij = prod_axes r(|i-j|),
// r(0) = 2dx/3, r(1) = dx/6 (N).
//
// The divergence is taken in split form: with H = H_ext + H_d,
//   div T = div T_self + mu0 (M . grad) H_ext,
//   T_self = mu0 (H_d + M) (x) H_d - (mu0/2)|H_d|^2 I,
// which equals div T exactly in the continuum (div H_ext = 0, curl H_ext = 0,
// div B = 0). Discretely it removes the cross terms H_ext (div B)_h and
// H_ext x (curl H_d)_h, whose truncation errors grow with the applied field
// and at H_ext = 1e6 A/m swamp the force between two bodies.
#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/grid_scratch.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/core/sources/magnet_interaction.h"

namespace lodestone {
inline namespace sources {
class FieldSource;
}  // namespace sources

inline namespace stage {

/// ForceMask::Material counts a node as material where n exceeds this
/// fraction of the grid's largest n: below it, n is round-off of B-spline
/// weights that are 0 in exact arithmetic (1e-30 and less measured), not matter.
constexpr double kMaskDustFraction = 1e-12;

enum class ForceMask : int {
  /// Keep t_j only at nodes within a few nodes of magnetic material
  /// (n > kMaskDustFraction * max n).
  /// Stress jumps at the surfaces of permanent magnets inside the grid then
  /// exert no force on empty space.
  Material = 0,
  /// Keep t_j everywhere (the sum then telescopes to the wall flux).
  None = 1
};
const char* toString(ForceMask mask);

/// t_j = div T at every node (N/m^3) from the total field H (A/m), the
/// induction B (T) and the applied field H_ext (A/m). Under
/// ForceMask::Material, t_j is kept where n > kMaskDustFraction max n within `dilation` nodes
/// (default 2: one node for the nodal gradient of phi, one for the central
/// difference, so the whole surface traction of the body is kept; measured
/// on two spheres, 0 nodes loses ~15% of their mutual force, 1 node ~1.5%,
/// 2 nodes ~0.4%). n may be empty when mask == None.
/// With `applied` (the source of H_ext), the term mu0 (M . grad) H_ext is
/// the source's own directional derivative at the node instead of a central
/// difference of the nodal H_ext: a difference across the surface of a
/// permanent magnet that the material touches would see H_ext's jump there
/// (it pushed a cube resting on a magnet away with 400 N). The derivative
/// is that of the field the material sees (field + exteriorContinuation, as
/// the magnetic stage samples H_ext), continuous across magnets' faces.
/// `scratch`, when given, holds the mask between calls (results are the same).
void stressDivergence(GridView<const Vec3d> H, GridView<const Vec3d> B, GridView<const Vec3d> Hext,
                      GridView<const double> n, ForceMask mask, GridView<Vec3d> t, int dilation = 2,
                      const FieldSource* applied = nullptr, double time = 0.0, GridScratch* scratch = nullptr);

/// mu0 (M . grad) H_s (N/m^3): the Kelvin force density that `source`
/// exerts on magnetization M (A/m) at x (m), the derivative taken of the
/// field the material sees (field + exteriorContinuation) over +-1e-3 dx
/// (one-sided where the continuation changes). The applied-field term of
/// stressDivergence.
Vec3d appliedFieldForceDensity(const FieldSource& source, const Vec3d& x, const Vec3d& M, double dx, double time);

/// The reaction of magnetized material on one field source: minus the force
/// (N) that `source` exerts on the material, the sum over nodes of dx^3 mu0
/// (M . grad) H_s, and minus its torque (N*m) about `centre`, the sum of
/// dx^3 [(x - c) x mu0 (M . grad) H_s + mu0 M x H_s] (the couple term: the
/// material's total couple M x H vanishes for the total field only).
/// materialM: the material's magnetization at the nodes (A/m), zero where
/// there is none. Independent of the thread count.
MagnetWrench sourceReaction(GridView<const Vec3d> materialM, const FieldSource& source, const Vec3d& centre,
                            double time);

/// Moves nodal forces f (N) that lie outside the support of the density
/// (n = 0) onto it: a node at distance L (26-connected node steps) splits its
/// force equally among its neighbours at distance L - 1, outermost first, so
/// the sum is kept. Forces farther than maxDistance are dropped and returned
/// (N). Used to hand a host conservative per-particle forces.
Vec3d gatherToSupport(GridView<const Vec3d> f, GridView<const double> n, GridView<Vec3d> out, int maxDistance = 6);

/// f_i = sum_j R_ij t_j (N); rows at the walls lose the weight of missing
/// neighbours. t and f may be the same grid. `scratch` as for projectedGradient.
void spreadForce(GridView<const Vec3d> t, GridView<Vec3d> f, GridScratch* scratch = nullptr);

}  // namespace stage
}  // namespace lodestone
