#include "farm_jobs.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>
#include <filesystem>
#include <map>
#include <sstream>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/output/atomic_file.h"
#include "run_directory.h"

namespace lodestone::examples {

namespace {

int statusOf(int waitStatus) {
  if (WIFEXITED(waitStatus)) return WEXITSTATUS(waitStatus);
  if (WIFSIGNALED(waitStatus)) return 128 + WTERMSIG(waitStatus);
  return 127;
}

// fork + exec; in the child, standard output (and error) to `log` (appended)
// or to the pipe `outFd`.
pid_t spawn(const std::vector<std::string>& args, const std::string& log, int outFd) {
  if (args.empty()) throw InvalidArgument("a job without a command");
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) throw Error(concat("cannot start '", args[0], "': ", std::strerror(errno)));
  if (pid == 0) {
    if (!log.empty()) {
      const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      if (fd < 0) ::_exit(127);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::close(fd);
    }
    if (outFd >= 0) ::dup2(outFd, 1);
    ::execvp(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

}  // namespace

std::vector<int> runPool(const std::vector<FarmJob>& jobs, int parallel,
                         const std::function<void(std::size_t, int)>& done) {
  require(parallel >= 1, "process pool: need at least one process at a time, got ", parallel);
  std::vector<int> status(jobs.size(), 127);
  std::map<pid_t, std::size_t> running;
  std::size_t next = 0;
  while (next < jobs.size() || !running.empty()) {
    while (next < jobs.size() && int(running.size()) < parallel) {
      running[spawn(jobs[next].args, jobs[next].log, -1)] = next;
      ++next;
    }
    int ws = 0;
    const pid_t pid = ::waitpid(-1, &ws, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      throw Error(concat("process pool: waitpid failed: ", std::strerror(errno)));
    }
    const auto it = running.find(pid);
    if (it == running.end()) continue;  // not one of ours
    status[it->second] = statusOf(ws);
    if (done) done(it->second, status[it->second]);
    running.erase(it);
  }
  return status;
}

std::string selfExecutable() {
  char path[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", path, sizeof path - 1);
  if (n <= 0) throw Error("cannot find the path of this program (/proc/self/exe)");
  return std::string(path, std::size_t(n));
}

int runCapture(const std::vector<std::string>& args, std::string* output) {
  int fds[2];
  if (::pipe(fds) != 0) throw Error(concat("cannot start '", args.at(0), "': ", std::strerror(errno)));
  const pid_t pid = spawn(args, "", fds[1]);
  ::close(fds[1]);
  std::string text;
  char buf[4096];
  ssize_t n = 0;
  while ((n = ::read(fds[0], buf, sizeof buf)) != 0) {
    if (n < 0) {
      if (errno == EINTR) continue;
      break;
    }
    text.append(buf, std::size_t(n));
  }
  ::close(fds[0]);
  int ws = 0;
  while (::waitpid(pid, &ws, 0) < 0 && errno == EINTR) {
  }
  if (output) *output = text;
  return statusOf(ws);
}

std::string arrayScript(const ArrayJob& job) {
  require(!job.taskCommands.empty(), "Slurm array '", job.name, "': no tasks");
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "#SBATCH --job-name=" << job.name << "\n"
    << "#SBATCH --array=0-" << job.taskCommands.size() - 1 << "\n"
    << "#SBATCH --output=" << job.logDir << "/" << job.name << "_%a.log\n"
    << "#SBATCH --open-mode=append\n"
    << "#SBATCH --requeue\n";
  if (!job.partition.empty()) s << "#SBATCH --partition=" << job.partition << "\n";
  for (const std::string& a : job.sbatchArgs) {
    if (a.size() < 2 || a[0] != '-' || a.find('\n') != std::string::npos)
      throw InvalidArgument(concat("--sbatch-args '", a, "': give each sbatch option as one argument, like ",
                                   "--sbatch-args=--account=fx"));
    s << "#SBATCH " << a << "\n";
  }
  s << "# Task i runs line i below; a requeued task runs it again (the commands\n"
    << "# continue from their own checkpoints).\n"
    << "set -eu\n"
    << "echo \"task $SLURM_ARRAY_TASK_ID on $(hostname), start $(date -u +%FT%TZ), restart ${SLURM_RESTART_COUNT:-0}\"\n"
    << "case \"$SLURM_ARRAY_TASK_ID\" in\n";
  for (std::size_t i = 0; i < job.taskCommands.size(); ++i) s << "  " << i << ") " << job.taskCommands[i] << " ;;\n";
  s << "  *) echo \"no task $SLURM_ARRAY_TASK_ID\" >&2; exit 1 ;;\n"
    << "esac\n";
  return s.str();
}

SubmittedArray submitArray(const ArrayJob& job, const std::string& scriptPath, bool wait) {
  std::filesystem::create_directories(job.logDir);
  output::writeFileAtomically(scriptPath, arrayScript(job));
  std::filesystem::permissions(scriptPath, std::filesystem::perms::owner_exec, std::filesystem::perm_options::add);
  std::vector<std::string> args{"sbatch", "--parsable"};
  if (wait) args.push_back("--wait");
  args.push_back(scriptPath);
  std::string out;
  const int status = runCapture(args, &out);
  if (status == 127)
    throw Error(concat("cannot run sbatch (", commandLine(args),
                       "): is Slurm installed and its commands on PATH? (docs/farm.md)"));
  std::string id = out.substr(0, out.find_first_of(";\n"));
  if (status != 0 && !(wait && !id.empty()))
    throw Error(concat("sbatch failed with status ", status, " (", commandLine(args), ")"));
  if (id.empty()) throw Error(concat("sbatch printed no job id (", commandLine(args), ")"));
  return {id, status};
}

}  // namespace lodestone::examples
