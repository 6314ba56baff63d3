#pragma once
// A superposition of applied-field sources, itself a FieldSource: the applied
// field H_ext of PHYSICS.md section 2 is the sum of the fields of coils and
// magnets, and the permanent magnetization the sum of the magnets'. Owns its
// sources; copying the set clones every source.
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/sources/field_source.h"

namespace lodestone {
inline namespace sources {

class FieldSourceSet final : public FieldSource {
 public:
  FieldSourceSet() = default;
  FieldSourceSet(const FieldSourceSet& other);
  FieldSourceSet& operator=(const FieldSourceSet& other);
  FieldSourceSet(FieldSourceSet&&) noexcept = default;
  FieldSourceSet& operator=(FieldSourceSet&&) noexcept = default;
  ~FieldSourceSet() override = default;

  /// Takes ownership; throws InvalidArgument for a null pointer.
  void add(std::unique_ptr<FieldSource> source);
  /// Adds a clone of `source`.
  void add(const FieldSource& source);

  std::size_t size() const { return sources_.size(); }
  bool empty() const { return sources_.empty(); }
  /// Source i (0 <= i < size(), else InvalidArgument); mutable to move magnets.
  FieldSource& source(std::size_t i);
  const FieldSource& source(std::size_t i) const;

  /// Sum of the sources' fields (A/m); zero for an empty set.
  Vec3d field(const Vec3d& x, double t) const override;
  /// Sum of the sources' magnetizations (A/m).
  Vec3d magnetization(const Vec3d& x, double t) const override;
  /// Sum of the sources' exterior continuations (A/m).
  Vec3d exteriorContinuation(const Vec3d& x, double t) const override;
  /// Adds every source's field at the points to `out` (A/m). Const and free
  /// of shared scratch, so threads may call it at once on disjoint outputs.
  void accumulateField(const Vec3d* x, std::size_t count, double t, Vec3d* out) const override;
  /// True when every source is uniform (and for an empty set, whose field is zero).
  bool isUniform() const override;
  /// The count and every source's signature; false when any source has none.
  bool appendFieldSignature(double t, std::vector<double>& out) const override;
  /// "N field sources: [0] ...; [1] ...".
  std::string describe() const override;
  std::unique_ptr<FieldSource> clone() const override;

 private:
  std::vector<std::unique_ptr<FieldSource>> sources_;
};

}  // namespace sources
}  // namespace lodestone
