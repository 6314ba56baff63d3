#pragma once
// Reusable temporaries of the nodal-field and force passes: a few z planes
// per thread for projectedGradient and recoverNodalFields (scalar0), a
// whole-grid vector field for spreadForce (vector0; tens to hundreds of MB at
// 128^3 to 256^3). A caller that runs them repeatedly on one grid keeps one
// GridScratch, so that these buffers are allocated once instead of being
// mapped, page-faulted and cleared by the kernel on every call.
#include <vector>

#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace base {

struct GridScratch {
  std::vector<double> scalar0, scalar1;
  std::vector<Vec3d> vector0;
};

}  // namespace base
}  // namespace lodestone
