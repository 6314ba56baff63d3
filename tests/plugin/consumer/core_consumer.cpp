// A C++ host of the installed core: a ball of the paper's material
// rasterized into a density grid, solved next to a spherical magnet with
// runOnDensity; it must be pulled toward the magnet (-z).
#include <cmath>
#include <cstdio>

#include "lodestone/core/field/material.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/stage/density_raster.h"
#include "lodestone/core/stage/magnetic_stage.h"

int main() {
  using namespace lodestone;
  GridSpec g;
  g.dx = 0.01;
  g.origin = {-0.08, -0.08, -0.08};
  g.dims = {17, 17, 17};
  const MagneticMaterial material = paperMaterial();
  const DenseGrid<double> n = rasterizeDensity(g, material.numberDensity, [](const Vec3d& x) {
    return norm2(x) < 0.03 * 0.03;
  });
  MagneticForceStage stage(g, material);
  const MagneticStageReport r =
      stage.runOnDensity(n.view(), SphereMagnet(Pose::at({0, 0, -0.12}), 0.03, {0, 0, 8e5}), 0.0);
  std::printf("core consumer: converged %d, total force (%g, %g, %g) N\n", int(r.converged()), r.totalForce.x,
              r.totalForce.y, r.totalForce.z);
  return r.converged() && r.totalForce.z < 0 && std::fabs(r.totalForce.x) < 1e-6 * -r.totalForce.z ? 0 : 1;
}
