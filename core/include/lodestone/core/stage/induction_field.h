#pragma once
// The magnetic induction B (T) at any point of space, composed of the two
// parts a run knows: the applied sources' closed form everywhere,
// B_src = mu0 (H_src + M_src) (exact inside magnets too), plus the material's
// part B - B_src interpolated trilinearly from a nodal grid inside the grid's
// box (zero outside it: the material's far field beyond the padded solve box
// is left out). Subtracting the sources before interpolating keeps the
// interpolated part smooth (the sources' field, steep near magnets and
// discontinuous across their faces, is never interpolated), so field lines
// traced through it follow the closed form exactly where there is no
// material. Safe to evaluate from many threads at once.
#include <memory>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/core/sources/field_source.h"

namespace lodestone {
inline namespace stage {

class MagneticForceStage;

class InductionField {
 public:
  /// The sources alone at time t (s); the sources are cloned.
  InductionField(const FieldSource& sources, double time);
  /// The sources plus the material's part (T, one value per node).
  InductionField(const FieldSource& sources, double time, DenseGrid<Vec3d> materialPart);
  /// The sources at `time` (s) plus the material's part of the stage's last
  /// run: its nodal B less the sources' B at the nodes at the time of that
  /// run (stage.time()). `sources` must be those of that run (a host that
  /// solves once per frame or substep interval gets the applied field of
  /// `time` and the material's response of its last solve; magnets that
  /// moved since then are subtracted at their current pose, which the
  /// solver keeps within its re-solve distance).
  static InductionField ofStage(const MagneticForceStage& stage, const FieldSource& sources, double time);

  InductionField(const InductionField& other);
  InductionField& operator=(const InductionField& other);
  InductionField(InductionField&&) noexcept = default;
  InductionField& operator=(InductionField&&) noexcept = default;
  ~InductionField() = default;

  /// B (T) at world position x (m).
  Vec3d operator()(const Vec3d& x) const;
  /// The sources' part mu0 (H_src + M_src) alone (T).
  Vec3d sourcesPart(const Vec3d& x) const;
  /// The material's part (T): trilinear inside the grid's box, zero outside.
  Vec3d materialPart(const Vec3d& x) const;
  /// The material grid (empty when there is none).
  const DenseGrid<Vec3d>& materialGrid() const { return material_; }
  double time() const { return time_; }

 private:
  std::unique_ptr<FieldSource> sources_;
  double time_ = 0;
  DenseGrid<Vec3d> material_;
};

}  // namespace stage
}  // namespace lodestone
