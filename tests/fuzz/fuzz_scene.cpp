// libFuzzer harness: scene files from arbitrary text. parseScene must either
// return a scene or throw lodestone::Error (syntax errors with line and
// column, unknown keys, wrong types, out-of-range values, grids too large);
// any other exception, a crash, or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const lodestone::plugin::Scene scene = lodestone::plugin::parseScene(text, "fuzz.json");
    (void)scene.frameDuration();
  } catch (const lodestone::Error&) {
    // A clear refusal is the expected outcome for most inputs.
  }
  return 0;
}
