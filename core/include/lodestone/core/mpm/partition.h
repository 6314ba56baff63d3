#pragma once
// One MPM simulation shared by several processes (MpmSolver::setPartition).
// Core defines what the solver needs of the other processes; dist/ provides
// it over MPI and PETSc (dist/mpm_partition.h, docs/distributed.md). Core
// never includes MPI.
//
// The MPM grid is split into boxes of nodes, one per process. A process owns
// the particles whose stencil base node (floor((x - origin)/dx - 1/2) per
// axis, the node MpmGrid bins a particle by) lies in its box, and holds the
// grid on its window: its box widened by three nodes on each side (clipped
// to the grid), which covers every node its particles' 3x3x3 stencils reach
// and, for surface tension's colour Hessian, their neighbours.
// A substep of a partitioned solver:
//   - migrate: particles whose base node left the box go to their new owner;
//   - P2G on the window, then sumNodes: every window node gets the sum of the
//     mass and momentum all processes deposited on it (with surface tension,
//     the colour field is summed the same way first, sumScalars);
//   - the grid update on the whole window (a node held by several processes
//     gets the same velocity on each: same sums, same rules);
//   - G2P of the process's own particles from its window.
// A dynamic rigid body's momentum exchange gathers its coupling nodes and
// the particles pushed out of it from every process (allGather) and runs on
// each. Reductions make the time step, the frame's energies and counts, and
// the field-solve decisions the same on every process. The calls that
// exchange data (migrate, gatherToRoot, the sums, the reductions and
// allGather) are collective: all processes make them, in the same order.
#include <cstdint>
#include <string>
#include <vector>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/mpm/grid.h"
#include "lodestone/core/mpm/particles.h"

namespace lodestone {
inline namespace mpm {

class MpmPartition {
 public:
  virtual ~MpmPartition() = default;

  /// This process's rank, 0..ranks()-1, and the number of processes.
  virtual int rank() const = 0;
  virtual int ranks() const = 0;

  /// The box of nodes this process owns, [boxLo, boxHi) in the global
  /// grid's node indices (the boxes of all processes tile the grid).
  virtual Index3 boxLo() const = 0;
  virtual Index3 boxHi() const = 0;
  /// The window of nodes this process holds, [windowLo, windowHi) in the
  /// global grid's node indices.
  virtual Index3 windowLo() const = 0;
  virtual Index3 windowHi() const = 0;

  /// The rank that owns a particle at x (m): the process whose box holds
  /// its stencil base node (x inside the grid's particle range).
  virtual int owner(const Vec3d& x) const = 0;

  /// Sends every particle this process holds but does not own to its owner
  /// and appends those it receives (collective). Returns how many it sent.
  virtual std::size_t migrate(MpmParticles& particles) = 0;

  /// Moves every particle to rank 0 (collective): rank 0 then holds the whole
  /// simulation's particles (for output), the others none. The next substep's
  /// migrate hands them back to their owners.
  virtual void gatherToRoot(MpmParticles& particles) = 0;

  /// `window` holds one MpmNode per window node (x fastest; `count` of them);
  /// afterwards every entry is the sum over the processes of what they
  /// deposited there.
  virtual void sumNodes(MpmNode* window, std::size_t count) = 0;

  /// `window` holds one value per window node (`count` of them); afterwards
  /// every entry is the sum over the processes (the colour field of surface
  /// tension).
  virtual void sumScalars(double* window, std::size_t count) = 0;

  /// One line: how the grid is split and what this process holds.
  virtual std::string describe() const = 0;

  /// The largest value over the processes.
  virtual double maxOverRanks(double value) = 0;
  /// Sums n values element-wise over the processes, in place.
  virtual void sumOverRanks(double* values, int n) = 0;
  /// Every process's `local` array, concatenated in rank order, on every
  /// process.
  virtual std::vector<double> allGather(const std::vector<double>& local) = 0;
};

/// A 64-bit key (a particle id, a node's flat index) carried bit for bit in
/// one double of an exchanged record, and back.
double keyAsDouble(std::uint64_t key);
std::uint64_t keyOf(double value);

/// Every process's records of `width` values (collective, allGather), each
/// with its key in its first value (keyAsDouble), ordered by key: the same
/// order whatever the number of processes.
std::vector<double> allGatherByKey(MpmPartition& partition, const std::vector<double>& local, std::size_t width);

}  // namespace mpm
}  // namespace lodestone
