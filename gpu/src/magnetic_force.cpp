#include "lodestone/gpu/magnetic_force.h"

#include <vector>

#include "device_entry.h"
#include "field_kernels.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
namespace gpu {

namespace {
void hostMagneticForce(const kernels::Dims& g, const MagnetizationLaw<double>& law, const MagneticForceInput& in,
                       const MagneticForceOutput& out) {
  const std::size_t count = g.nodes();
  std::vector<Vec3d> H(count), B(count), a(count), b(count);
  for (std::size_t m = 0; m < count; ++m) kernels::nodalFieldsAt(g, law, in.phi, in.hext, in.n, m, H[m], B[m]);
  if (out.H) std::copy(H.begin(), H.end(), out.H);
  if (out.B) std::copy(B.begin(), B.end(), out.B);
  if (!out.force) return;
  for (std::size_t m = 0; m < count; ++m)
    a[m] = kernels::stressDivergenceAt(g, H.data(), B.data(), in.hext, in.n, in.maskMaterial, in.dilation, m);
  for (int axis = 0; axis < 3; ++axis) {
    for (std::size_t m = 0; m < count; ++m) b[m] = kernels::spreadAxisAt(g, a.data(), axis, m);
    a.swap(b);
  }
  std::copy(a.begin(), a.end(), out.force);
}
}  // namespace

Backend magneticForce(const GridSpec& grid, const MagnetizationLaw<double>& law, const MagneticForceInput& in,
                      const MagneticForceOutput& out, Backend backend) {
  grid.validate("gpu magnetic force grid");
  require(in.phi && in.hext && in.n, "gpu magnetic force: phi, H_ext and n are all required");
  require(in.dilation >= 0 && in.dilation <= 8, "gpu magnetic force: mask dilation must be 0..8 nodes, got ",
          in.dilation);
  const Backend used = resolveBackend(backend);
  kernels::Dims g;
  g.nx = grid.dims.i;
  g.ny = grid.dims.j;
  g.nz = grid.dims.k;
  g.dx = grid.dx;
  if (used == Backend::Cuda)
    detail::deviceMagneticForce(g, law, in, out);
  else
    hostMagneticForce(g, law, in, out);
  return used;
}

}  // namespace gpu
}  // namespace lodestone
