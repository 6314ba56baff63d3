#pragma once
// Particle order: every MpmSettings::reorderInterval substeps, and after the
// first substep that follows an emission, the solver sorts its particles by
// grid cell, so that P2G and G2P walk the particle
// arrays in the order they touch the grid (memory locality). The order is
// the one the last P2G binned the particles in (MpmGrid::binnedOrder:
// stencil base nodes in flat order, ascending old index within a node), a
// function of the positions and the current order alone, so the same on
// every run and for any thread count.
//
// Sorting is a permutation: every attribute of a particle moves with it
// (MpmParticles::permute; `id` is the identity that survives), and so does
// anything else the solver keeps per particle index (the field-reuse record).
#include <cstdint>
#include <vector>

#include "lodestone/core/mpm/field_reuse.h"
#include "lodestone/core/mpm/particles.h"

namespace lodestone {
inline namespace mpm {

/// Whether the particles are sorted once `substeps` substeps have been taken
/// (counting the one just finished): every `interval` substeps, and after
/// the first substep that follows an emission (`emittedSinceSort`: a body's
/// points lie in its emitter's lattice order, in which a P2G took 1.6 times
/// as long as in cell order); never when `interval` is 0.
bool particleReorderDue(int interval, long long substeps, bool emittedSinceSort = false);

/// Sorts the particles into `order` (new particle p is old particle
/// order[p]; the binned order of the last P2G) and permutes `reuse`'s record
/// with them; an identity `order` (particles already in cell order) moves
/// nothing. When `order` no longer describes the particles (its size
/// differs: particles were removed after the P2G that made it) nothing
/// changes and false is returned. Throws InvalidArgument when `order` is not
/// a permutation.
bool reorderParticles(const std::vector<std::uint32_t>& order, MpmParticles& particles, FieldReuse& reuse);

}  // namespace mpm
}  // namespace lodestone
