#include "rank_job.h"

#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "lodestone/core/base/error.h"

#if LODESTONE_HAVE_DIST
#include <mpi.h>

#include "lodestone/dist/mpm_partition.h"
#include "lodestone/dist/petsc_session.h"
#endif

namespace lodestone {

bool startedByMpiLauncher() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(v)) return true;
  return false;
}

#if LODESTONE_HAVE_DIST
struct RankJob::Mpi {
  int argc = 1;
  char name[16] = "lodestone";
  char* argvStorage[2] = {name, nullptr};
  char** argv = argvStorage;
  PetscSession session{&argc, &argv};  // PETSc options from PETSC_OPTIONS only
};

RankJob::RankJob() {
  if (!startedByMpiLauncher()) return;
  mpi_ = std::make_unique<Mpi>();
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks_);
}

RankJob::~RankJob() = default;

std::shared_ptr<MpmPartition> RankJob::partitionOf(const GridSpec& grid) const {
  if (ranks_ < 2) return nullptr;
  return std::make_shared<PetscMpmPartition>(MPI_COMM_WORLD, grid);
}

int RankJob::threadsPerRank() const {
  if (ranks_ < 2) return 0;
  const long online = sysconf(_SC_NPROCESSORS_ONLN);
  int bound = 0;  // the CPUs this process may run on
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0) bound = CPU_COUNT(&set);
  if (bound > 0 && bound < online) return bound;  // the launcher bound it
  // Processes on this node: Open MPI says; Slurm's "32(x4)" starts with it.
  const char* local = std::getenv("OMPI_COMM_WORLD_LOCAL_SIZE");
  if (!local) local = std::getenv("SLURM_NTASKS_PER_NODE");
  const int perNode = local && std::atoi(local) > 0 ? std::atoi(local) : ranks_;
  return std::max(1, int(online) / perNode);
}

bool RankJob::anyRank(bool flag) const {
  if (ranks_ < 2) return flag;
  int mine = flag ? 1 : 0, any = 0;
  MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  return any != 0;
}

void execUnderMpirun(int ranks, const std::vector<std::string>& args) {
  std::vector<std::string> command{"mpirun", "-n", std::to_string(ranks), "--oversubscribe"};
  if (geteuid() == 0) command.push_back("--allow-run-as-root");  // containers and CI run as root
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  command.push_back(ec ? args.at(0) : self.string());
  // --ranks stays: the processes see it agree with their launcher, and the
  // run directory records the command as given.
  for (std::size_t i = 1; i < args.size(); ++i) command.push_back(args[i]);
  std::vector<char*> argv;
  for (std::string& s : command) argv.push_back(s.data());
  argv.push_back(nullptr);
  execvp(argv[0], argv.data());
  throw Error(concat("--ranks ", ranks, ": cannot start mpirun (", std::strerror(errno),
                     "); install Open MPI (Debian: openmpi-bin) or start the job yourself: mpirun -n ", ranks,
                     " lodestone run ..."));
}
#else
struct RankJob::Mpi {};

RankJob::RankJob() {
  const char* size = std::getenv("OMPI_COMM_WORLD_SIZE");
  if (!size) size = std::getenv("PMI_SIZE");
  if (size && std::atoi(size) > 1)
    throw Error(concat("started as one of ", size,
                       " MPI processes, but this lodestone was built without PETSc and MPI (LODESTONE_PETSC=OFF): "
                       "every process would run the whole scene; install petsc-dev, libopenmpi-dev and openmpi-bin "
                       "and rebuild"));
}

RankJob::~RankJob() = default;

std::shared_ptr<MpmPartition> RankJob::partitionOf(const GridSpec&) const { return nullptr; }

int RankJob::threadsPerRank() const { return 0; }

bool RankJob::anyRank(bool flag) const { return flag; }

void execUnderMpirun(int ranks, const std::vector<std::string>&) {
  throw Error(concat("--ranks ", ranks,
                     " needs a lodestone built with PETSc and MPI (LODESTONE_PETSC=ON; install petsc-dev, "
                     "libopenmpi-dev and openmpi-bin and rebuild)"));
}
#endif

}  // namespace lodestone
