#pragma once
// `lodestone run` on several processes (docs/distributed.md): under an MPI
// launcher (mpirun, or srun in a Slurm allocation) every process runs the
// same command; the MPM is split over them (dist/mpm_partition.h), rank 0
// writes every file and prints, the others print nothing. `--ranks N` starts
// such a job from a plain command line.
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/mpm/solver.h"

namespace lodestone {

class RankJob {
 public:
  /// Joins the MPI job this process was started in (MPI and PETSc start
  /// here, PETSc options from PETSC_OPTIONS only), or is a job of one when
  /// no MPI launcher started it. Throws Error when this lodestone was built
  /// without MPI but was started by an MPI launcher with several processes.
  RankJob();
  ~RankJob();
  RankJob(const RankJob&) = delete;
  RankJob& operator=(const RankJob&) = delete;

  int rank() const { return rank_; }
  int ranks() const { return ranks_; }
  /// Whether this process writes the run's files (rank 0).
  bool writes() const { return rank_ == 0; }
  /// The split of an MPM grid over the job (collective), for buildSolver;
  /// null for a job of one.
  std::shared_ptr<MpmPartition> partitionOf(const GridSpec& grid) const;
  /// Worker threads for this process when --threads is not given: 0 (all
  /// cores) for a job of one; otherwise the CPUs the launcher bound it to
  /// (srun, or mpirun without oversubscription), or when it bound none the
  /// node's CPUs divided by the processes on the node (at least 1).
  int threadsPerRank() const;
  /// Whether any process has `flag` set (collective with several processes).
  bool anyRank(bool flag) const;

 private:
  struct Mpi;
  std::unique_ptr<Mpi> mpi_;
  int rank_ = 0, ranks_ = 1;
};

/// Whether an MPI launcher started this process (its environment says so).
bool startedByMpiLauncher();

/// `lodestone run --ranks N`: replaces this process with `mpirun -n N
/// --oversubscribe [--allow-run-as-root] <this program> ARGS`, ARGS being
/// `args` (the command line, program name first, --ranks included). Throws
/// Error when mpirun cannot be started or this lodestone has no MPI.
[[noreturn]] void execUnderMpirun(int ranks, const std::vector<std::string>& args);

}  // namespace lodestone
