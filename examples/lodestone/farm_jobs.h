#pragma once
// Running many `lodestone` processes: on this machine as a process pool, or
// on a Slurm cluster as one job array (sbatch --array, one task per job).
// Used by `lodestone wedge` and `lodestone farm-post` (docs/farm.md).
#include <functional>
#include <string>
#include <vector>

namespace lodestone::examples {

/// One process: its arguments (argv[0] a path) and the file its standard
/// output and error go to (appended; "" keeps the caller's).
struct FarmJob {
  std::vector<std::string> args;
  std::string log;
};

/// Runs the jobs, at most `parallel` (>= 1) at a time, in order of their
/// index. Returns each job's exit status (128 + N for a job ended by signal
/// N, 127 when it could not be started). `done` (optional) is called as
/// each ends, with its index and status.
std::vector<int> runPool(const std::vector<FarmJob>& jobs, int parallel,
                         const std::function<void(std::size_t, int)>& done = {});

/// The path of the running program (/proc/self/exe).
std::string selfExecutable();

/// Runs `args` and returns its exit status; its standard output goes to
/// `output` (when not null). Throws lodestone::Error when it cannot start.
int runCapture(const std::vector<std::string>& args, std::string* output);

/// A Slurm job array: task i runs taskCommands[i] (a shell command line).
struct ArrayJob {
  std::string name;                       ///< --job-name
  std::string logDir;                     ///< task i logs to logDir/NAME_i.log (appended across requeues)
  std::vector<std::string> taskCommands;  ///< one shell command line per task
  std::string partition;                  ///< "" = the cluster's default
  std::vector<std::string> sbatchArgs;    ///< more sbatch options, one argument each ("--account=fx")
};

/// The batch script of the array (bash; #SBATCH lines: job name, array
/// 0..n-1, output, --requeue, --open-mode=append, partition, then each of
/// sbatchArgs). Throws lodestone::InvalidArgument naming an sbatch argument
/// that is not one option ("fx" without its --account=).
std::string arrayScript(const ArrayJob& job);

/// A submitted array: its job id, and with sbatch --wait its exit status
/// (the highest of its tasks'; 0 without --wait).
struct SubmittedArray {
  std::string id;
  int status = 0;
};

/// Writes the script to `scriptPath` and submits it with sbatch (with
/// `wait`: sbatch --wait, which returns when every task has ended). Throws
/// lodestone::Error when sbatch refuses it or is not installed.
SubmittedArray submitArray(const ArrayJob& job, const std::string& scriptPath, bool wait);

}  // namespace lodestone::examples
