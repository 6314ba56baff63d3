#pragma once
// Reusable temporaries of the nodal-field and force passes: a few z planes
// per thread for projectedGradient and recoverNodalFields (scalar0) and for
// spreadForce (vector1), spreadForce's copy of its input when it is also its
// output (vector0, whole-grid), the force's material mask (mask0, mask1; a
// byte a node). A caller that runs them repeatedly on one grid keeps one
// GridScratch, so that these buffers are allocated once instead of being
// mapped, page-faulted and cleared by the kernel on every call.
#include <cstdint>
#include <vector>

#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace base {

struct GridScratch {
  std::vector<double> scalar0;
  std::vector<Vec3d> vector0, vector1;
  std::vector<std::uint8_t> mask0, mask1;  // stressDivergence's material mask
};

}  // namespace base
}  // namespace lodestone
