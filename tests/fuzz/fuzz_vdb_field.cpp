// libFuzzer harness: VDB field files from arbitrary bytes. The bytes are
// written to a scratch file and read with every field reader (scalar n,
// vector H, density with its checks) onto a small grid. Readers must return
// or throw lodestone::Error; anything else is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "bounded_new.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/grid.h"
#include "lodestone/vdb_io/field_file.h"

namespace {
std::string scratchPath() { return "/tmp/lodestone_fuzz_field_" + std::to_string(::getpid()) + ".vdb"; }
}  // namespace

// OpenVDB 10's readTopology leaks the nodes it had allocated when a read
// throws half-way (RootNode.h, InternalNode.h): an upstream leak on the
// error path, so leak detection is off for the VDB harnesses only.
extern "C" const char* __asan_default_options() { return "allocator_may_return_null=1:detect_leaks=0"; }

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = scratchPath();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  if (size > 0) std::fwrite(data, 1, size, f);
  std::fclose(f);
  const lodestone::GridSpec spec{{-0.02, -0.02, -0.02}, 0.005, {9, 9, 9}};
  try {
    (void)lodestone::readScalarField(path, "n", spec);
  } catch (const lodestone::Error&) {
  }
  try {
    (void)lodestone::readDensityVdb(path, spec);
  } catch (const lodestone::Error&) {
  }
  try {
    (void)lodestone::readVec3Field(path, "H", spec);
  } catch (const lodestone::Error&) {
  }
  return 0;
}
