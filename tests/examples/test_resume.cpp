// `lodestone run` checkpoints and --resume, end to end: a run killed with
// SIGKILL part-way and resumed from its last checkpoint writes the same frame
// files, byte for byte, as an uninterrupted run; SIGINT stops it cleanly with
// a message saying where and how to resume; corrupted checkpoints are
// skipped. The command's path comes from LODESTONE_CLI, the spike scene from
// LODESTONE_SCENES_DIR.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;

namespace {

const int kFrames = 10;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("lodestone_resume_" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<std::string> runArgs(const fs::path& out, bool resume) {
  std::vector<std::string> args = {LODESTONE_CLI,
                                   "run",
                                   std::string(LODESTONE_SCENES_DIR) + "/spike.json",
                                   "--out",
                                   out.string(),
                                   "--frames",
                                   "1:" + std::to_string(kFrames),
                                   "--checkpoint-every",
                                   "3",
                                   "--no-png",
                                   "--threads",
                                   "2"};
  if (resume) args.push_back("--resume");
  return args;
}

// Starts the command with stdout/stderr to `log`; returns its pid.
pid_t start(const std::vector<std::string>& args, const fs::path& log) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::FILE* f = std::freopen(log.string().c_str(), "w", stdout);
    if (f) ::dup2(::fileno(stdout), 2);
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

int wait(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
}

int runToEnd(const std::vector<std::string>& args, const fs::path& log) { return wait(start(args, log)); }

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Waits (up to 120 s) until `file` exists; false on timeout.
bool waitFor(const fs::path& file) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!fs::exists(file)) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

fs::path frame(const fs::path& dir, int f) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%04d.ply", f);
  return dir / name;
}

}  // namespace

TEST(Resume, KilledRunResumesToTheSameFramesBitForBit) {
  const fs::path ref = scratch("reference"), cut = scratch("killed");
  ASSERT_EQ(runToEnd(runArgs(ref, false), ref.parent_path() / "reference.log"), 0)
      << readText(ref.parent_path() / "reference.log");

  // Kill hard as soon as the second checkpoint (frame 6) is on disk: the
  // run is then somewhere in frame 7, with no chance to clean up.
  const pid_t pid = start(runArgs(cut, false), cut.parent_path() / "killed.log");
  ASSERT_TRUE(waitFor(cut / "checkpoint_0006.lsck"));
  ::kill(pid, SIGKILL);
  EXPECT_EQ(wait(pid), 128 + SIGKILL);
  EXPECT_FALSE(fs::exists(frame(cut, kFrames))) << "the run finished before it was killed";
  // Atomic writes: every frame file the killed run left is complete (equal
  // to the uninterrupted run's); at most a hidden temporary is left over.
  int kept = 0;
  for (int f = 0; f <= kFrames; ++f)
    if (fs::exists(frame(cut, f))) {
      ++kept;
      EXPECT_TRUE(readText(frame(ref, f)) == readText(frame(cut, f))) << "killed run's frame " << f;
    }
  EXPECT_GE(kept, 7);  // frames 0..6 at least

  const fs::path resumeLog = cut.parent_path() / "resumed.log";
  ASSERT_EQ(runToEnd(runArgs(cut, true), resumeLog), 0) << readText(resumeLog);
  EXPECT_NE(readText(resumeLog).find("resuming from"), std::string::npos) << readText(resumeLog);
  for (int f = 0; f <= kFrames; ++f) {
    ASSERT_TRUE(fs::exists(frame(cut, f))) << frame(cut, f);
    EXPECT_TRUE(readText(frame(ref, f)) == readText(frame(cut, f))) << "frame " << f << " differs";
  }
  EXPECT_TRUE(readText(ref / "checkpoint_0009.lsck") == readText(cut / "checkpoint_0009.lsck"));
  fs::remove_all(ref.parent_path());
}

TEST(Resume, CorruptedCheckpointIsSkippedForTheOlderOne) {
  const fs::path ref = scratch("corrupt_ref"), dir = scratch("corrupt");
  ASSERT_EQ(runToEnd(runArgs(ref, false), ref.parent_path() / "corrupt_ref.log"), 0);
  // Keep checkpoints 3 and 6; flip one byte of 6's payload.
  fs::copy_file(ref / "checkpoint_0003.lsck", dir / "checkpoint_0003.lsck");
  std::string bytes = readText(ref / "checkpoint_0006.lsck");
  bytes[bytes.size() / 2] = char(bytes[bytes.size() / 2] ^ 0x10);
  std::ofstream(dir / "checkpoint_0006.lsck", std::ios::binary) << bytes;
  const fs::path log = dir.parent_path() / "corrupt.log";
  ASSERT_EQ(runToEnd(runArgs(dir, true), log), 0) << readText(log);
  const std::string text = readText(log);
  EXPECT_NE(text.find("checksum mismatch"), std::string::npos) << text;
  EXPECT_NE(text.find("checkpoint_0003.lsck: frame 3"), std::string::npos) << text;
  EXPECT_TRUE(readText(frame(ref, kFrames)) == readText(frame(dir, kFrames)));
  // Nothing to resume from: a clear error.
  const fs::path empty = scratch("empty");
  const fs::path emptyLog = empty.parent_path() / "empty.log";
  EXPECT_EQ(runToEnd(runArgs(empty, true), emptyLog), 1);
  EXPECT_NE(readText(emptyLog).find("no usable checkpoint"), std::string::npos) << readText(emptyLog);
  fs::remove_all(ref.parent_path());
}

TEST(Resume, SigintStopsCleanlyAndSaysHowToResume) {
  const fs::path dir = scratch("sigint");
  const fs::path log = dir.parent_path() / "sigint.log";
  const pid_t pid = start(runArgs(dir, false), log);
  ASSERT_TRUE(waitFor(dir / "checkpoint_0003.lsck"));
  ::kill(pid, SIGINT);
  EXPECT_EQ(wait(pid), 130) << readText(log);
  const std::string text = readText(log);
  EXPECT_NE(text.find("interrupted: stopped"), std::string::npos) << text;
  EXPECT_NE(text.find("--resume"), std::string::npos) << text;
  EXPECT_NE(text.find("at t = "), std::string::npos) << text;
  // stats.json is complete JSON (written atomically after every frame).
  const std::string stats = readText(dir / "stats.json");
  ASSERT_FALSE(stats.empty());
  EXPECT_EQ(stats.find_last_not_of(" \n"), stats.rfind('}'));
  fs::remove_all(dir.parent_path());
}
