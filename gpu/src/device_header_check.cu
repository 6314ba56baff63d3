// Compiles every core LODESTONE_HOSTDEV function the backend relies on as
// device code, in double and float, so that a core change that breaks device
// compilation (a host-only std:: call, a missing qualifier) fails the build.
// The kernel is never launched.
#include <cuda_runtime.h>

#include "lodestone/core/base/bspline.h"
#include "lodestone/core/field/langevin.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/base/mat3.h"
#include "lodestone/core/base/symmetric_eigen.h"
#include "lodestone/core/field/q1_axis_weights.h"
#include "lodestone/core/mpm/apic_gather.h"
#include "lodestone/core/mpm/collider.h"
#include "lodestone/core/mpm/constitutive.h"
#include "lodestone/core/field/q1_element.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
namespace gpu {
namespace detail {

template <typename T>
__device__ T exerciseLangevin(T a) {
  const LangevinTriple<T> t = langevinTriple(a);
  return langevin(a) + langevinOverArg(a) + langevinDerivative(a) + logSinhOverArg(a) + t.overArg + t.derivative +
         t.logSinhc;
}

template <typename T>
__device__ T exerciseBspline(T u) {
  const QuadraticWeights<T> w = quadraticWeights(u, T(2));
  return quadraticBaseFloor(u) + w.w[0] + w.dw[2];
}

__global__ void headerCheckKernel(double* out, float* outf, MagnetizationLaw<double> law, BoundaryCondition bc) {
  const double a = 0.5 + threadIdx.x;
  out[0] = exerciseLangevin(a) + exerciseBspline(a);
  outf[0] = exerciseLangevin(float(a)) + exerciseBspline(float(a));
  const Vec3d H{a, 2.0, -1.0};
  const MagnetizationResponse<double> r = respond(law, 1e23, H);
  out[1] = r.W + r.dMdH.trace() + coEnergy(law, 1e23, H) + magnetization(law, 1e23, H).x + law.saturation(1.0) +
           law.lowFieldSusceptibility(1.0) + norm(H) + double(isFinite(H)) + dot(cross(H, H), H);
  double v[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  const q1::Tables t = q1::makeTables();
  out[2] = q1::referenceGradient(t, int(threadIdx.x & 7u), v).x + q1::interpolate(t, 1, v);
  Mat3d F = Mat3d::identity() * Mat3d::outer(H, H).transposed();
  out[3] = neoHookeanKirchhoff(F, 1.0, 2.0)(0, 0) + neoHookeanCauchy(F, 1.0, 2.0)(1, 1) +
           neoHookeanEnergyDensity(F, 1.0, 2.0) + viscousFluidKirchhoff(F, 1.0, 0.1, 1e5)(2, 2) +
           viscousFluidCauchy(F, 1.0, 0.1, 1e5)(0, 1) + fluidEnergyDensity(0.9, 1e5) + determinant(F) + trace(F) +
           viscoplasticFluidKirchhoff(F, 1.0, 10.0, 1.0, 0.5, 1e3, 1e5)(0, 2) +
           elastoplasticKirchhoff(vonMisesReturn(F, 1.0, 0.5), F, 1.0, 2.0, 0.1)(0, 1) + henckyEnergyDensity(F, 1.0, 2.0) +
           vonMisesStress(henckyKirchhoff(F, 1.0, 2.0));
  outf[1] = symmetricEigen(Mat3<float>::outer(Vec3<float>{1.f, 2.f, float(a)}, Vec3<float>{1.f, 2.f, 3.f})).values[0] +
            vonMisesReturn(Mat3<float>::identity(), 1.f, 0.5f)(0, 0);
  out[4] = applyBoundaryCondition(H, Vec3d{}, Vec3d{0, 0, 1}, bc).z;
  const int idx[3] = {int(threadIdx.x), 1, 2}, dims[3] = {8, 8, 8};
  out[5] = applyDomainWalls(H, idx, dims, 2, bc).x;
  double s[6];
  q1::gradientProducts(t, 1, int(threadIdx.x & 7u), s);
  out[6] = s[0] + s[5] + q1::laplacianDiagonal(8, 8, 8, 0.1, 1, 2, int(threadIdx.x & 7u)) +
           q1::laplacianRow(8, 8, 8, 0.1, 1, 2, 3, v) + q1::laplacianRow(8, 8, 8, 0.1, 0, 0, 0, outf);
  Vec3d vel[64];
  for (int m = 0; m < 64; ++m) vel[m] = H * double(m);
  const double u[3] = {1.3, 1.6, 1.2};
  const int b3[3] = {0, 0, 0};
  Vec3d vp;
  Mat3d C;
  gatherApic(vel, 4, 4, u, b3, 40.0, vp, C);
  out[7] = vp.x + C(1, 2);
}

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
