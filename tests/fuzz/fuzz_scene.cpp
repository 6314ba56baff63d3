// libFuzzer harness: scene files from arbitrary text. parseScene must either
// return a scene or throw lodestone::Error (syntax errors with line and
// column, unknown keys, wrong types, out-of-range values, grids too large);
// any other exception, a crash, or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  // Shapes stored in files are refused here: the harness fuzzes the scene
  // text, not whatever files a mutated path may name (fuzz_vdb_* cover the
  // readers).
  lodestone::plugin::SceneOptions options;
  options.loaders.levelSet = [](const std::string& path, const std::string&)
      -> std::shared_ptr<const lodestone::SampledSdf> {
    throw lodestone::InvalidArgument("level set '" + path + "': file shapes are not read by this harness");
  };
  options.loaders.mesh = [](const std::string& path, double) -> std::shared_ptr<const lodestone::SampledSdf> {
    throw lodestone::InvalidArgument("mesh '" + path + "': file shapes are not read by this harness");
  };
  try {
    const lodestone::plugin::Scene scene = lodestone::plugin::parseScene(text, "fuzz.json", options);
    (void)scene.frameDuration();
  } catch (const lodestone::Error&) {
    // A clear refusal is the expected outcome for most inputs.
  }
  return 0;
}
