#pragma once
// Named accuracy presets: the knobs of the magnetic stage that trade accuracy
// for time, set together from the measurements of docs/accuracy_vs_time.md.
//
//   preset   bound  Newton tolerance  field solves
//   draft    10 %   1e-2              once per frame
//   preview   5 %   1e-3              every 5 substeps
//   final     1 %   1e-6              every substep
//
// `bound` is the relative deviation from the converged answer (the same
// grid, field solved every substep to 1e-10) that the preset's settings
// stayed within in every study of the report (interior field, force,
// trajectories); it is also the planner's accuracy budget. The grid spacing
// is not part of a preset: it is the scene's (the report gives the error of
// each resolution separately).
#include <string>

#include "lodestone/core/field/field_solver.h"

namespace lodestone {
inline namespace planner {

enum class AccuracyPreset : int { Draft = 0, Preview = 1, Final = 2 };

struct AccuracyPresetSettings {
  AccuracyPreset preset = AccuracyPreset::Final;
  const char* name = "final";
  double bound = 0.01;           ///< relative deviation from the converged answer (dimensionless)
  double solveTolerance = 1e-6;  ///< Newton tolerance (FieldSolveSettings::tolerance)
  int solveInterval = 1;         ///< substeps between field solves (0 = once per frame)
  const char* description = "";
};

const char* toString(AccuracyPreset preset);
/// The settings of a preset.
AccuracyPresetSettings accuracyPresetSettings(AccuracyPreset preset);
/// "draft", "preview" or "final"; throws InvalidArgument naming the bad name and the valid ones.
AccuracyPreset parseAccuracyPreset(const std::string& name);

}  // namespace planner
}  // namespace lodestone
