#pragma once
// Entry points of the CUDA translation units used by the host-side glue;
// no_cuda.cpp defines them (throwing) when CUDA is not built.
#include "field_kernels.h"
#include "lodestone/gpu/magnetic_force.h"

namespace lodestone {
namespace gpu {
namespace detail {

void deviceMagneticForce(const kernels::Dims& g, const MagnetizationLaw<double>& law, const MagneticForceInput& in,
                         const MagneticForceOutput& out);

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
