// libFuzzer harness: VDB particle files (OpenVDB PointDataGrid "points")
// from arbitrary bytes, through readParticlesVdb. It must return particles
// or throw lodestone::Error; anything else is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "bounded_new.h"
#include "lodestone/core/base/error.h"
#include "lodestone/vdb_io/point_file.h"

// OpenVDB 10's readTopology leaks the nodes it had allocated when a read
// throws half-way (RootNode.h, InternalNode.h): an upstream leak on the
// error path, so leak detection is off for the VDB harnesses only.
extern "C" const char* __asan_default_options() { return "allocator_may_return_null=1:detect_leaks=0"; }

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/tmp/lodestone_fuzz_points_" + std::to_string(::getpid()) + ".vdb";
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  if (size > 0) std::fwrite(data, 1, size, f);
  std::fclose(f);
  try {
    const lodestone::ParticleVdbData p = lodestone::readParticlesVdb(path);
    (void)p.size();
  } catch (const lodestone::Error&) {
  }
  return 0;
}
