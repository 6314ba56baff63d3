#include "lodestone/core/planner/accuracy_preset.h"

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace planner {

const char* toString(AccuracyPreset preset) {
  switch (preset) {
    case AccuracyPreset::Draft: return "draft";
    case AccuracyPreset::Preview: return "preview";
    case AccuracyPreset::Final: return "final";
  }
  return "unknown";
}

AccuracyPresetSettings accuracyPresetSettings(AccuracyPreset preset) {
  AccuracyPresetSettings s;
  s.preset = preset;
  s.name = toString(preset);
  switch (preset) {
    case AccuracyPreset::Draft:
      s.bound = 0.10;
      s.solveTolerance = 1e-2;
      s.solveInterval = 0;
      s.description = "blocking and look development: one loose field solve per frame";
      break;
    case AccuracyPreset::Preview:
      s.bound = 0.05;
      s.solveTolerance = 1e-3;
      s.solveInterval = 5;
      s.description = "dailies: the field follows the motion every 5 substeps";
      break;
    case AccuracyPreset::Final:
      s.bound = 0.01;
      s.solveTolerance = 1e-6;
      s.solveInterval = 1;
      s.description = "final frames: a converged field every substep";
      break;
    default:
      throw InvalidArgument(concat("accuracy preset: unknown value ", int(preset)));
  }
  return s;
}

AccuracyPreset parseAccuracyPreset(const std::string& name) {
  for (AccuracyPreset p : {AccuracyPreset::Draft, AccuracyPreset::Preview, AccuracyPreset::Final})
    if (name == toString(p)) return p;
  throw InvalidArgument(concat("accuracy preset '", name, "' is not one of draft, preview, final"));
}

}  // namespace planner
}  // namespace lodestone
