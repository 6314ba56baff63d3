#pragma once
// Nodal fields and the magnetic force from a solved potential, on the device
// or the host reference: the pipeline of core's recoverNodalFields,
// stressDivergence and spreadForce (core/src/stage/nodal_field.cpp,
// magnetic_force.cpp):
//   H = H_ext - grad phi (lumped-L2 projected gradient), B = mu0 (H + M(H; n)),
//   t = div T in split form (Einstein-Laub stress, central differences;
//       (M . grad) H_ext from central differences of the nodal H_ext),
//   f_i = sum_j R_ij t_j with R = prod_axes [dx/6, 2dx/3, dx/6] (N).
// Arrays are host arrays, one entry per node, x fastest.
#include "lodestone/core/base/grid.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/gpu/backend.h"

namespace lodestone {
namespace gpu {

struct MagneticForceInput {
  const double* phi = nullptr;  ///< potential of the field solve, A
  const Vec3d* hext = nullptr;  ///< applied field at the nodes, A/m
  const double* n = nullptr;    ///< micro-particle density, 1/m^3
  bool maskMaterial = true;     ///< keep div T only within `dilation` nodes of n > 0 (ForceMask::Material)
  int dilation = 2;             ///< nodes, 0..8
};

struct MagneticForceOutput {
  Vec3d* H = nullptr;      ///< A/m (may be null)
  Vec3d* B = nullptr;      ///< T (may be null)
  Vec3d* force = nullptr;  ///< nodal force, N (may be null)
};

/// Computes the outputs on the chosen backend (Auto: the device when present).
/// Throws InvalidArgument on missing inputs or a bad dilation, Error when
/// Cuda is requested without a usable device. Returns the backend that ran.
Backend magneticForce(const GridSpec& grid, const MagnetizationLaw<double>& law, const MagneticForceInput& in,
                      const MagneticForceOutput& out, Backend backend = Backend::Auto);

}  // namespace gpu
}  // namespace lodestone
