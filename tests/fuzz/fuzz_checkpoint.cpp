// libFuzzer harness: checkpoint files from arbitrary bytes. A solver is built
// from a small scene (the one the seed checkpoint was written for) and
// restoreMpmCheckpoint must either restore it or throw lodestone::Error and
// leave it unchanged; a restored solver must take a substep. Inputs with an
// odd first byte get a valid header (see below) to reach the payload parser.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/hash.h"
#include "lodestone/core/mpm/checkpoint.h"
#include "lodestone/plugin/scene.h"

namespace {
const char* kScene = R"({
  "name": "tiny",
  "domain": {"min": [0, 0, 0], "max": [0.08, 0.08, 0.08], "dx": 0.01},
  "time": {"frames": 1, "fps": 100},
  "materials": [{"name": "ferro", "model": "fluid", "density": 2500, "viscosity": 1, "bulk_modulus": 200000,
                 "magnetic": {"law": "paper"}}],
  "bodies": [{"material": "ferro", "shape": "box", "center": [0.04, 0.04, 0.03], "half_size": [0.005, 0.005, 0.005],
              "particles_per_cell": 1}],
  "fields": [{"type": "uniform", "H": [0, 0, 10000]}],
  "output": {"png": false, "ply": false, "vdb_points": true, "checkpoint_every": 1}
})";

// A valid header around `payload` (magic, version, byte order, size, FNV-1a
// checksum as mpm_checkpoint.h lays it out), so that mutations reach the
// payload parser instead of stopping at the checksum.
std::vector<std::uint8_t> wrapPayload(const std::uint8_t* payload, std::size_t size) {
  std::vector<std::uint8_t> out(32 + size);
  std::memcpy(out.data(), "LDSTCKPT", 8);
  const std::uint32_t version = lodestone::kMpmCheckpointVersion, bom = 0x01020304u;
  const std::uint64_t bytes = size, hash = lodestone::fnv1a64(payload, size);
  std::memcpy(out.data() + 8, &version, 4);
  std::memcpy(out.data() + 12, &bom, 4);
  std::memcpy(out.data() + 16, &bytes, 8);
  std::memcpy(out.data() + 24, &hash, 8);
  if (size > 0) std::memcpy(out.data() + 32, payload, size);
  return out;
}
}  // namespace

// Inputs starting with an odd byte are a payload (after that byte) wrapped in
// a valid header; others are taken as a whole file.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* input, std::size_t inputSize) {
  std::vector<std::uint8_t> wrapped;
  const std::uint8_t* data = input;
  std::size_t size = inputSize;
  if (inputSize > 0 && (input[0] & 1) != 0) {
    wrapped = wrapPayload(input + 1, inputSize - 1);
    data = wrapped.data();
    size = wrapped.size();
  }
  static const lodestone::plugin::Scene scene = lodestone::plugin::parseScene(kScene, "tiny.json");
  std::unique_ptr<lodestone::MpmSolver> solver = lodestone::plugin::buildSolver(scene);
  const std::size_t before = solver->particles().size();
  try {
    (void)lodestone::readMpmCheckpointInfo(data, size);
  } catch (const lodestone::Error&) {
  }
  try {
    lodestone::restoreMpmCheckpoint(*solver, data, size);
  } catch (const lodestone::Error&) {
    if (solver->particles().size() != before || solver->time() != 0) __builtin_trap();  // half-restored
    return 0;
  }
  try {
    solver->step(1e-5);
  } catch (const lodestone::Error&) {
    // Restored values are validated by the step (e.g. a non-finite position throws or is removed).
  }
  return 0;
}
