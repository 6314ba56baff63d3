#pragma once
// `lodestone surface DIR`: surfaces, meshes and render volumes for the
// particle cache (particles_NNNN.vdb) of a finished or running run
// directory, frames in parallel.
#include <string>

#include "outputs.h"

namespace lodestone::examples {

struct SurfaceCommandArgs {
  std::string dir;
  std::string outputs = "surface,mesh,volume";  ///< of surface, mesh, volume
  int first = 0, last = 0;  ///< frames; last = 0: all of the cache
  std::string method;       ///< "" : the scene's output.surface.method
  double voxelSize = -1;    ///< m; < 0: the scene's output.surface.voxel_size
  int threads = 0;
};

/// Returns the exit code; throws lodestone::Error on a bad directory.
int surfaceCommand(const SurfaceCommandArgs& args);

}  // namespace lodestone::examples
