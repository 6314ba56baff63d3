#pragma once
// Field reuse: the effects planner's "reuse the field while material barely
// moved" (docs/planner.md), as the MPM solver applies it. A field solve is
// due on the solver's interval (MpmSettings::magneticSolveInterval, or once
// per frame); when the plan of the last solve allows reuse
// (MagneticPlan::reuseDistance > 0), the due solve is skipped and the last
// nodal force kept while both
//
//   |x_p - x_p^0| <= reuseDistance   for every magnetic point p, and
//   max_q |H(x_q^0, t) - H_q^0| / max_q |H_q^0| <= reuseFieldChange
//                                    (relativeFieldChange, effects_planner.h)
//
// hold, x_p^0 being the positions at the last solve and H_q^0 the applied
// field then at a sample of the magnetic points (every max(1, N/256)-th of
// the N magnetic points: all of them when N < 512, else 256 to 511). The
// applied field is sampled where the points were at the last solve, so the
// second test sees only the field's own change (moving magnets, time
// profiles); the first sees the material's motion.
//
// FieldReuse is the record both tests compare against. Its positions are
// indexed like the particles, so it is permuted with them (permute) when the
// solver reorders them; a record whose size differs from the particle count
// (particles were added or removed since) never allows reuse.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "lodestone/core/base/vec3.h"
#include "lodestone/core/sources/field_source.h"

namespace lodestone {
inline namespace mpm {

class FieldReuse {
 public:
  /// Records the state of a field solve at time t (s): `positions` of every
  /// particle (m), `magneticPoints` the indices of the magnetic ones among
  /// them (ascending), and the applied field (A/m) at the sampled ones.
  void record(const std::vector<Vec3d>& positions, const std::vector<std::uint32_t>& magneticPoints,
              const FieldSource& applied, double t);

  /// First test: true when the record holds `positions.size()` particles and
  /// at least one sample, and no particle p with isMagnetic(p) lies farther
  /// than `distance` (m) from its recorded position. Non-magnetic particles
  /// may move freely.
  template <typename IsMagnetic>
  bool pointsWithin(const std::vector<Vec3d>& positions, const IsMagnetic& isMagnetic, double distance) const {
    if (positions_.size() != positions.size() || samples_.empty()) return false;
    const double d2 = distance * distance;
    for (std::size_t p = 0; p < positions.size(); ++p)
      if (isMagnetic(p) && norm2(positions[p] - positions_[p]) > d2) return false;
    return true;
  }

  /// Second test: true when the applied field at time t (s), sampled at the
  /// recorded sample positions, differs from the recorded samples by at most
  /// `tolerance` (relativeFieldChange). The caller poses anything the field
  /// depends on (magnets) at t first. Requires pointsWithin to have held
  /// (a record with samples).
  bool fieldWithin(const FieldSource& applied, double t, double tolerance) const;

  /// Follows a reordering of the particles: new particle p is old particle
  /// order[p] (`order` a permutation of the recorded particles). A record of
  /// another size is left as it is (it allows no reuse anyway).
  void permute(const std::vector<std::uint32_t>& order);

  /// The record: every particle's position at the last solve (m), the
  /// particle indices of the samples and the applied field there (A/m).
  const std::vector<Vec3d>& positions() const { return positions_; }
  const std::vector<std::uint32_t>& samples() const { return samples_; }
  const std::vector<Vec3d>& fields() const { return fields_; }

  /// Replaces the record with one read back from a checkpoint, which checked
  /// it: samples index positions (or there are no positions), one field per
  /// sample.
  void restore(std::vector<Vec3d> positions, std::vector<std::uint32_t> samples, std::vector<Vec3d> fields);

 private:
  std::vector<Vec3d> positions_;        // every particle at the last solve, m
  std::vector<std::uint32_t> samples_;  // particle indices of the sampled magnetic points
  std::vector<Vec3d> fields_;           // applied field at those samples at the last solve, A/m
};

}  // namespace mpm
}  // namespace lodestone
