// A C++ host of the installed vdb_io: the fields of a solved ball written to
// a .vdb file and its density read back, node for node.
#include <cstdio>
#include <string>

#include "lodestone/core/field/material.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/core/stage/density_raster.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/vdb_io/field_file.h"

int main(int argc, char** argv) {
  using namespace lodestone;
  if (argc != 2) return 2;
  GridSpec g;
  g.dx = 0.01;
  g.origin = {-0.05, -0.05, -0.05};
  g.dims = {11, 11, 11};
  const MagneticMaterial material = paperMaterial();
  const DenseGrid<double> n = rasterizeDensity(g, material.numberDensity, [](const Vec3d& x) {
    return norm2(x) < 0.025 * 0.025;
  });
  MagneticForceStage stage(g, material);
  stage.runOnDensity(n.view(), UniformField({0, 0, 1e4}), 0.0);
  const std::string path = argv[1];
  writeFieldsVdb(path, stage, VdbFrameMetadata{});
  const DenseGrid<double> back = readDensityVdb(path, g);
  double worst = 0;
  for (std::size_t m = 0; m < g.nodeCount(); ++m) {
    const double d = (back.view()[m] - n.view()[m]) / material.numberDensity;
    worst = d > worst ? d : (-d > worst ? -d : worst);
  }
  std::printf("vdb consumer: density read back within %g of n0\n", worst);
  return worst < 1e-6 ? 0 : 1;
}
