// The record of the last field solve that the MPM solver's reuse test
// compares against; see field_reuse.h.
#include "lodestone/core/mpm/field_reuse.h"

#include <algorithm>
#include <utility>

#include "lodestone/core/planner/effects_planner.h"

namespace lodestone {
inline namespace mpm {

void FieldReuse::record(const std::vector<Vec3d>& positions, const std::vector<std::uint32_t>& magneticPoints,
                        const FieldSource& applied, double t) {
  positions_ = positions;
  samples_.clear();
  const std::size_t stride = std::max<std::size_t>(1, magneticPoints.size() / 256);
  for (std::size_t q = 0; q < magneticPoints.size(); q += stride) samples_.push_back(magneticPoints[q]);
  fields_.resize(samples_.size());
  for (std::size_t q = 0; q < samples_.size(); ++q) fields_[q] = applied.field(positions[samples_[q]], t);
}

bool FieldReuse::fieldWithin(const FieldSource& applied, double t, double tolerance) const {
  std::vector<Vec3d> H(samples_.size());
  for (std::size_t q = 0; q < H.size(); ++q) H[q] = applied.field(positions_[samples_[q]], t);
  return !(relativeFieldChange(H, fields_) > tolerance);
}

void FieldReuse::permute(const std::vector<std::uint32_t>& order) {
  if (positions_.size() != order.size()) return;
  std::vector<Vec3d> moved(positions_.size());
  std::vector<std::uint32_t> newIndex(order.size());
  for (std::size_t p = 0; p < order.size(); ++p) {
    moved[p] = positions_[order[p]];
    newIndex[order[p]] = std::uint32_t(p);
  }
  positions_.swap(moved);
  for (std::uint32_t& q : samples_) q = newIndex[q];
}

void FieldReuse::restore(std::vector<Vec3d> positions, std::vector<std::uint32_t> samples, std::vector<Vec3d> fields) {
  positions_ = std::move(positions);
  samples_ = std::move(samples);
  fields_ = std::move(fields);
}

}  // namespace mpm
}  // namespace lodestone
