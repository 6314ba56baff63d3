// Sorting the MPM particles by grid cell; see particle_order.h.
#include "lodestone/core/mpm/particle_order.h"

namespace lodestone {
inline namespace mpm {

bool particleReorderDue(int interval, long long substeps, bool emittedSinceSort) {
  return interval > 0 && (emittedSinceSort || substeps % interval == 0);
}

bool reorderParticles(const std::vector<std::uint32_t>& order, MpmParticles& particles, FieldReuse& reuse) {
  if (order.size() != particles.size()) return false;
  particles.permute(order);  // validates the permutation before anything moves
  reuse.permute(order);
  return true;
}

}  // namespace mpm
}  // namespace lodestone
