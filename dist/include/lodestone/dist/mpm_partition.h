#pragma once
// The MPM of one scene split over the ranks of an MPI job on PETSc: core's
// MpmPartition (mpm/partition.h) with
//   - the grid a PETSc DMDA (one node per grid node, 4 values: momentum and
//     mass; box stencil of width 2, the reach of a quadratic B-spline stencil
//     from its base node), split by PETSC_DECIDE; a rank owns the DMDA's box
//     of nodes and holds its ghosted box as the window;
//   - P2G ghost accumulation by DMLocalToGlobal(ADD_VALUES) and the sums
//     handed back to every window by DMGlobalToLocal(INSERT_VALUES); the
//     colour field of surface tension the same way on a second DMDA of one
//     value per node over the same boxes;
//   - particle migration by a DMSwarm (basic type; one record of 33 values
//     per particle: x, v, C, F, J, mass, V0, n_p, material, id, magnetic
//     force) and DMSwarmMigrate: each rank puts the particles that leave it
//     into the swarm with their new owner's rank; between migrations they
//     live in core's MpmParticles, which the transfers read.
// docs/distributed.md describes the decomposition and what runs distributed.
#include <mpi.h>

#include <cstddef>
#include <memory>
#include <string>

#include "lodestone/core/mpm/partition.h"

namespace lodestone {
inline namespace dist {

class PetscMpmPartition final : public MpmPartition {
 public:
  /// Splits the MPM grid `grid` over the ranks of `comm` (collective; PETSc
  /// must be running, PetscSession). Throws Error when PETSc cannot split
  /// the grid (a rank's box would be thinner than the stencil's 2 nodes).
  PetscMpmPartition(MPI_Comm comm, const GridSpec& grid);
  ~PetscMpmPartition() override;
  PetscMpmPartition(const PetscMpmPartition&) = delete;
  PetscMpmPartition& operator=(const PetscMpmPartition&) = delete;

  int rank() const override;
  int ranks() const override;
  Index3 boxLo() const override;
  Index3 boxHi() const override;
  Index3 windowLo() const override;
  Index3 windowHi() const override;
  int owner(const Vec3d& x) const override;
  std::size_t migrate(MpmParticles& particles) override;
  void gatherToRoot(MpmParticles& particles) override;
  void sumNodes(MpmNode* window, std::size_t count) override;
  void sumScalars(double* window, std::size_t count) override;
  double maxOverRanks(double value) override;
  void sumOverRanks(double* values, int n) override;
  std::vector<double> allGather(const std::vector<double>& local) override;

  /// Ranks per axis, e.g. {1, 1, 2}.
  Index3 rankGrid() const;
  /// One line: the ranks per axis and this rank's box and window.
  std::string describe() const override;
  /// Particles this rank sent in migrations (not counting gatherToRoot).
  std::size_t sent() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dist
}  // namespace lodestone
