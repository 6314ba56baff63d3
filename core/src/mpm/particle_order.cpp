// Sorting the MPM particles by grid cell; see particle_order.h.
#include "lodestone/core/mpm/particle_order.h"

#include <algorithm>

namespace lodestone {
inline namespace mpm {

bool particleReorderDue(int interval, long long substeps, bool emittedSinceSort) {
  return interval > 0 && (emittedSinceSort || substeps % interval == 0);
}

bool reorderParticles(const std::vector<std::uint32_t>& order, MpmParticles& particles, FieldReuse& reuse) {
  if (order.size() != particles.size()) return false;
  // Already in cell order (a body that moved as a whole since the last
  // sort): the permutation is the identity and nothing moves.
  std::uint32_t p = 0;
  if (std::all_of(order.begin(), order.end(), [&p](std::uint32_t o) { return o == p++; })) return true;
  particles.permute(order);  // validates the permutation before anything moves
  reuse.permute(order);
  return true;
}

}  // namespace mpm
}  // namespace lodestone
