// `lodestone run` checkpoints and --resume, end to end: a run killed with
// SIGKILL part-way and resumed from its last checkpoint writes the same frame
// files, byte for byte, as an uninterrupted run; SIGINT stops it cleanly with
// a message saying where and how to resume; corrupted checkpoints are
// skipped. The command's path comes from LODESTONE_CLI, the spike and jet
// scenes from LODESTONE_SCENES_DIR.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#if LODESTONE_TEST_HAVE_VDB
#include <openvdb/openvdb.h>
#endif

#include "lodestone_test/scratch_dir.h"

namespace fs = std::filesystem;

namespace {

const int kFrames = 10;

fs::path scratch(const std::string& name) { return lodestone::test::scratchDir("resume", name); }

std::string spike() { return std::string(LODESTONE_SCENES_DIR) + "/spike.json"; }

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

// Starts the command with stdout/stderr to `log`; returns its pid. With
// `stdoutFd` >= 0, stdout goes there instead (stderr still to `log`).
pid_t start(const std::vector<std::string>& args, const fs::path& log, int stdoutFd = -1) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::FILE* f = std::freopen(log.string().c_str(), "w", stdout);
    if (f) ::dup2(::fileno(stdout), 2);
    if (stdoutFd >= 0) ::dup2(stdoutFd, 1);
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

// A scene whose material comes from an emitter over time: the chunks emitted
// by a time are a function of the time alone, so the resumed run emits what
// the uninterrupted one did and writes the same frames.
TEST(Resume, AnEmittingSceneResumesToTheSameFramesBitForBit) {
  const fs::path ref = scratch("jet_reference"), cut = scratch("jet_killed");
  const auto args = [](const fs::path& out, bool resume) {
    std::vector<std::string> a = {LODESTONE_CLI, "run", std::string(LODESTONE_SCENES_DIR) + "/ferrofluid_jet.json",
                                  "--out", out.string(), "--frames", "1:5", "--checkpoint-every", "2", "--no-png",
                                  "--threads", "2"};
    if (resume) a.push_back("--resume");
    return a;
  };
  ASSERT_EQ(runToEnd(args(ref, false), ref.parent_path() / "jet_reference.log"), 0)
      << readText(ref.parent_path() / "jet_reference.log");
  const pid_t pid = start(args(cut, false), cut.parent_path() / "jet_killed.log");
  ASSERT_TRUE(waitFor(cut / "checkpoint_0002.lsck"));
  ::kill(pid, SIGKILL);
  wait(pid);
  const fs::path resumeLog = cut.parent_path() / "jet_resumed.log";
  ASSERT_EQ(runToEnd(args(cut, true), resumeLog), 0) << readText(resumeLog);
  EXPECT_NE(readText(resumeLog).find("resuming from"), std::string::npos) << readText(resumeLog);
  EXPECT_GT(readText(frame(ref, 5)).size(), readText(frame(ref, 2)).size());  // it emitted after the checkpoint
  for (int f = 0; f <= 5; ++f) {
    ASSERT_TRUE(fs::exists(frame(cut, f))) << frame(cut, f);
    EXPECT_TRUE(readText(frame(ref, f)) == readText(frame(cut, f))) << "frame " << f << " differs";
  }
  fs::remove_all(ref.parent_path());
}

TEST(Resume, CorruptedCheckpointIsSkippedForTheOlderOne) {
  const fs::path ref = scratch("corrupt_ref"), dir = scratch("corrupt");
  ASSERT_EQ(runToEnd(runArgs(ref, false), ref.parent_path() / "corrupt_ref.log"), 0);
  // Keep checkpoints 3 and 6 (and the manifest saying which run wrote them);
  // flip one byte of 6's payload.
  fs::copy_file(ref / "lodestone_run.json", dir / "lodestone_run.json");
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

namespace {

// `lodestone run SCENE --out DIR --no-png --threads 2` and `extra`.
std::vector<std::string> args(const std::string& scene, const fs::path& out, std::vector<std::string> extra) {
  std::vector<std::string> a = {LODESTONE_CLI, "run", scene, "--out", out.string(), "--no-png", "--threads", "2"};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

// The spike scene with `from` replaced by `to`, written to `path`.
std::string sceneVariant(const fs::path& path, const std::string& from, const std::string& to) {
  std::string text = readText(spike());
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

}  // namespace

TEST(RunDirectory, ASecondRunIsRefusedWhileTheFirstWritesAndSigtermSaysHowToResume) {
  const fs::path dir = scratch("locked");
  const fs::path log = dir.parent_path() / "locked.log", second = dir.parent_path() / "second.log";
  const pid_t pid = start(args(spike(), dir, {"--frames", "1:40", "--dx", "0.015", "--checkpoint-every", "1"}), log);
  ASSERT_TRUE(waitFor(dir / "checkpoint_0002.lsck")) << readText(log);
  // Another scene into the same directory while the first writes: refused, naming the owner.
  const std::string other = sceneVariant(dir.parent_path() / "other.json", "\"viscosity\": 5.0", "\"viscosity\": 6.0");
  EXPECT_EQ(runToEnd(args(other, dir, {"--frames", "1:1", "--clean"}), second), 1) << readText(second);
  EXPECT_NE(readText(second).find("is in use: another lodestone run (pid " + std::to_string(pid) + ")"),
            std::string::npos)
      << readText(second);
  ::kill(pid, SIGTERM);
  EXPECT_EQ(wait(pid), 128 + SIGTERM) << readText(log);
  const std::string text = readText(log);
  // The resume command keeps the options that shape the run (--dx).
  EXPECT_TRUE(std::regex_search(text, std::regex("resume from checkpoint_[0-9]+\\.lsck .*with: lodestone run .*"
                                                 "--dx 0\\.015 --checkpoint-every 1 --resume")))
      << text;
  EXPECT_NE(readText(dir / "lodestone_run.json").find("\"status\": \"interrupted\""), std::string::npos);
  fs::remove_all(dir.parent_path());
}

TEST(RunDirectory, AnotherScenesOutputIsRefusedAndDeletedOnlyWithClean) {
  const fs::path dir = scratch("owned");
  const fs::path log = dir.parent_path() / "owned.log";
  ASSERT_EQ(runToEnd(args(spike(), dir, {"--frames", "1:3", "--dx", "0.02"}), log), 0) << readText(log);
  const std::string manifest = readText(dir / "lodestone_run.json");
  EXPECT_NE(manifest.find("\"scene_hash\""), std::string::npos) << manifest;
  EXPECT_NE(manifest.find("\"status\": \"complete\""), std::string::npos) << manifest;
  EXPECT_NE(manifest.find("--frames 1:3 --dx 0.02"), std::string::npos) << manifest;
  const std::string before = readText(frame(dir, 3));

  // The same scene name, changed content: refused, the old frames untouched.
  const std::string changed =
      sceneVariant(dir.parent_path() / "changed.json", "\"viscosity\": 5.0", "\"viscosity\": 6.0");
  EXPECT_EQ(runToEnd(args(changed, dir, {"--frames", "1:1", "--dx", "0.02"}), log), 1) << readText(log);
  EXPECT_NE(readText(log).find("holds the output of another run (lodestone_run.json): scene 'spike' has changed"),
            std::string::npos)
      << readText(log);
  EXPECT_NE(readText(log).find("--clean"), std::string::npos);
  EXPECT_TRUE(readText(frame(dir, 3)) == before);
  // Another grid of the same scene: refused too.
  EXPECT_EQ(runToEnd(args(spike(), dir, {"--frames", "1:1", "--dx", "0.025"}), log), 1) << readText(log);
  EXPECT_NE(readText(log).find("its grid is"), std::string::npos) << readText(log);

  // --clean: the earlier run's files go; only the new run's remain.
  std::ofstream(dir / "notes.txt") << "not lodestone's";
  ASSERT_EQ(runToEnd(args(changed, dir, {"--frames", "1:1", "--dx", "0.02", "--clean"}), log), 0) << readText(log);
  EXPECT_TRUE(fs::exists(frame(dir, 1)));
  EXPECT_FALSE(fs::exists(frame(dir, 2)));
  EXPECT_FALSE(fs::exists(frame(dir, 3)));
  EXPECT_TRUE(fs::exists(dir / "notes.txt"));
  EXPECT_NE(readText(dir / "lodestone_run.json").find("changed.json"), std::string::npos);

  // Output without a manifest (an unknown writer): refused unless --clean.
  const fs::path bare = scratch("bare");
  fs::copy_file(frame(dir, 1), frame(bare, 7));
  EXPECT_EQ(runToEnd(args(spike(), bare, {"--frames", "1:1", "--dx", "0.02"}), log), 1) << readText(log);
  EXPECT_NE(readText(log).find("no lodestone_run.json"), std::string::npos) << readText(log);
  fs::remove_all(dir.parent_path());
}

TEST(Resume, RefusesCheckpointsOfAChangedSceneOrBeyondTheFrames) {
  const fs::path dir = scratch("range");
  const fs::path log = dir.parent_path() / "range.log";
  ASSERT_EQ(runToEnd(args(spike(), dir, {"--frames", "1:6", "--dx", "0.02", "--checkpoint-every", "3"}), log), 0)
      << readText(log);
  // --frames 1:4: checkpoint 6 lies beyond, 3 is taken, frame 4 simulated.
  ASSERT_EQ(runToEnd(args(spike(), dir, {"--frames", "1:4", "--dx", "0.02", "--checkpoint-every", "3", "--resume"}),
                     log),
            0)
      << readText(log);
  std::string text = readText(log);
  EXPECT_NE(text.find("checkpoint_0006.lsck: frame 6 lies beyond --frames 1:4"), std::string::npos) << text;
  EXPECT_NE(text.find("checkpoint_0003.lsck: frame 3"), std::string::npos) << text;
  EXPECT_NE(text.find("wrote frames 1..4"), std::string::npos) << text;
  // At the last frame already: said, nothing simulated.
  ASSERT_EQ(runToEnd(args(spike(), dir, {"--frames", "1:3", "--dx", "0.02", "--resume"}), log), 0) << readText(log);
  EXPECT_NE(readText(log).find("nothing to simulate"), std::string::npos) << readText(log);

  // A checkpoint of the scene before it changed, in the changed scene's directory: refused.
  const fs::path other = scratch("range_changed");
  const std::string changed =
      sceneVariant(dir.parent_path() / "changed.json", "\"viscosity\": 5.0", "\"viscosity\": 6.0");
  ASSERT_EQ(runToEnd(args(changed, other, {"--frames", "1:1", "--dx", "0.02"}), log), 0) << readText(log);
  fs::copy_file(dir / "checkpoint_0003.lsck", other / "checkpoint_0003.lsck");
  EXPECT_EQ(runToEnd(args(changed, other, {"--frames", "1:6", "--dx", "0.02", "--resume"}), log), 1) << readText(log);
  text = readText(log);
  EXPECT_NE(text.find("checkpoint_0003.lsck: it belongs to another run: scene 'spike' has changed"), std::string::npos)
      << text;
  EXPECT_NE(text.find("no usable checkpoint"), std::string::npos) << text;
  fs::remove_all(dir.parent_path());
}

TEST(Resume, KeepCheckpointsPrunesTheOldest) {
  const fs::path dir = scratch("keep");
  const fs::path log = dir.parent_path() / "keep.log";
  ASSERT_EQ(runToEnd(args(spike(), dir,
                          {"--frames", "1:5", "--dx", "0.02", "--checkpoint-every", "1", "--keep-checkpoints", "2"}),
                     log),
            0)
      << readText(log);
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".lsck") left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{"checkpoint_0004.lsck", "checkpoint_0005.lsck"}));
  fs::remove_all(dir.parent_path());
}

TEST(RunOutcome, ABlownUpRunExitsWithThreeAndASummaryUnlessAllowed) {
  const fs::path dir = scratch("blown");
  const fs::path log = dir.parent_path() / "blown.log";
  // Gravity of 1e308 m/s^2: every particle's state overflows in the first frame.
  const std::string blown =
      sceneVariant(dir.parent_path() / "blown.json", "\"gravity\": [\n    0,\n    0,\n    -9.81\n  ]",
                   "\"gravity\": [0, 0, -1e308]");
  EXPECT_EQ(runToEnd(args(blown, dir, {"--frames", "1:3", "--dx", "0.02"}), log), 3) << readText(log);
  const std::string text = readText(log);
  EXPECT_TRUE(std::regex_search(text, std::regex("the simulation blew up: ([0-9]+) of its \\1 particles \\(100%\\) "
                                                 "were lost as non-finite by frame 1")))
      << text;
  EXPECT_FALSE(fs::exists(frame(dir, 2)));
  EXPECT_NE(readText(dir / "lodestone_run.json").find("\"status\": \"failed\""), std::string::npos);
  // Allowed: the run goes on and says what was lost.
  EXPECT_EQ(runToEnd(args(blown, dir, {"--frames", "1:2", "--dx", "0.02", "--max-lost", "1"}), log), 0)
      << readText(log);
  EXPECT_NE(readText(log).find("(100%) were lost as non-finite (within --max-lost 1)"), std::string::npos)
      << readText(log);
  fs::remove_all(dir.parent_path());
}

TEST(RunOutcome, ATimeStepOfTooManySubstepsIsRefusedUpFront) {
  const fs::path dir = scratch("substeps");
  const fs::path log = dir.parent_path() / "substeps.log";
  const std::string slow = sceneVariant(dir.parent_path() / "slow.json", "\"dt\": 5e-05", "\"dt\": 1e-12");
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(runToEnd(args(slow, dir, {"--frames", "1:1", "--dx", "0.02"}), log), 1) << readText(log);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 60.0);
  EXPECT_NE(readText(log).find("time.dt = 1e-12 s takes 2e+09 substeps per frame of 0.002 s"), std::string::npos)
      << readText(log);
  EXPECT_NE(readText(log).find("more than --max-substeps 100000"), std::string::npos) << readText(log);
  EXPECT_FALSE(fs::exists(frame(dir, 1)));
}

TEST(RunOutcome, AClosedStandardOutputStopsTheRunWithAMessage) {
  const fs::path dir = scratch("pipe");
  const fs::path log = dir.parent_path() / "pipe.log";
  int fds[2];
  ASSERT_EQ(::pipe2(fds, O_CLOEXEC), 0);  // the command keeps only its stdout end
  const pid_t pid = start(args(spike(), dir, {"--frames", "1:20", "--dx", "0.02"}), log, fds[1]);
  ::close(fds[1]);
  ::close(fds[0]);  // what `| head -n 0` does
  EXPECT_EQ(wait(pid), 128 + SIGPIPE) << readText(log);
  EXPECT_NE(readText(log).find("standard output was closed (broken pipe): stopped after frame 1"), std::string::npos)
      << readText(log);
  EXPECT_TRUE(fs::exists(frame(dir, 1)));
  fs::remove_all(dir.parent_path());
}

namespace {

// A small scene in which nothing depends on the time (a jelly cube under
// gravity), from frame `startFrame`; the frame (1/64 s) and the substep
// (1/1024 s) are powers of two, so that the times add up exactly from any
// start and the frames are the same bit for bit.
std::string jellyScene(const fs::path& path, int startFrame, int frames) {
  std::ofstream(path) << R"({
  "name": "jelly",
  "domain": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.2], "dx": 0.02 },
  "time": { "start_frame": )" << startFrame << R"(, "frames": )" << frames << R"(, "fps": 64, "dt": 0.0009765625 },
  "materials": [ { "name": "jelly", "model": "solid", "density": 1000, "youngs_modulus": 1e4 } ],
  "bodies": [ { "material": "jelly", "shape": "box", "center": [0.1, 0.1, 0.1], "half_size": [0.03, 0.03, 0.03] } ]
})";
  return path.string();
}

// What follows a PLY file's header (the header's comment names the frame and time).
std::string plyBody(const fs::path& path) {
  const std::string text = readText(path);
  const std::size_t end = text.find("end_header\n");
  EXPECT_NE(end, std::string::npos) << path;
  return end == std::string::npos ? std::string() : text.substr(end + 11);
}

fs::path plyOf(const fs::path& dir, const std::string& number) { return dir / ("frame_" + number + ".ply"); }

}  // namespace

// time.start_frame 1001: the initial state is frame 1000, the frames 1001 and
// 1002; files, stats.json and messages use these numbers, and the state
// equals that of the same scene from frame 1 (nothing in it depends on the time).
TEST(StartFrame, ARunWritesTheScenesFrameNumbersAndTheSameStateAsFromFrameOne) {
  const fs::path one = scratch("start_1"), later = scratch("start_1001");
  const fs::path log = later.parent_path() / "start.log";
  ASSERT_EQ(runToEnd(args(jellyScene(one.parent_path() / "jelly_1.json", 1, 2), one, {}), log), 0) << readText(log);
  ASSERT_EQ(runToEnd(args(jellyScene(later.parent_path() / "jelly_1001.json", 1001, 2), later, {}), log), 0)
      << readText(log);
  EXPECT_NE(readText(log).find("wrote frames 1001..1002"), std::string::npos) << readText(log);
  for (const char* n : {"1000", "1001", "1002"}) EXPECT_TRUE(fs::exists(plyOf(later, n))) << n;
  EXPECT_FALSE(fs::exists(plyOf(later, "0000")));
  EXPECT_FALSE(fs::exists(plyOf(later, "0001")));
  const std::string stats = readText(later / "stats.json");
  EXPECT_TRUE(std::regex_search(stats, std::regex("\"frame\":\\s*1001[^0-9]"))) << stats;
  EXPECT_TRUE(std::regex_search(stats, std::regex("\"frame\":\\s*1002[^0-9]"))) << stats;
  EXPECT_FALSE(std::regex_search(stats, std::regex("\"frame\":\\s*[0-2][^0-9]"))) << stats;
  const std::string manifest = readText(later / "lodestone_run.json");
  EXPECT_TRUE(std::regex_search(manifest, std::regex("\"last_complete_frame\":\\s*1002"))) << manifest;
  EXPECT_NE(readText(plyOf(later, "1002")).find("frame 1002 time 15.65625 s"), std::string::npos);
  // The same particles, bit for bit.
  EXPECT_TRUE(plyBody(plyOf(one, "0000")) == plyBody(plyOf(later, "1000")));
  EXPECT_TRUE(plyBody(plyOf(one, "0002")) == plyBody(plyOf(later, "1002")));
  EXPECT_FALSE(plyBody(plyOf(later, "1000")) == plyBody(plyOf(later, "1002")));  // it moved
  // --frames takes scene frame numbers: 1002 alone (1001 still simulated).
  const fs::path part = scratch("start_part");
  ASSERT_EQ(runToEnd(args(later.parent_path() / "jelly_1001.json", part, {"--frames", "1002:1002"}), log), 0)
      << readText(log);
  EXPECT_FALSE(fs::exists(plyOf(part, "1000")));
  EXPECT_FALSE(fs::exists(plyOf(part, "1001")));
  EXPECT_TRUE(readText(plyOf(part, "1002")) == readText(plyOf(later, "1002")));
  fs::remove_all(one.parent_path());
}

// Checkpoints carry the scene frame number; --resume from checkpoint_1002
// writes the frames of the uninterrupted run, byte for byte.
TEST(StartFrame, AResumedRunWritesTheFramesOfTheUninterruptedOne) {
  const fs::path ref = scratch("start_ref"), cut = scratch("start_resumed");
  const fs::path log = ref.parent_path() / "start_resume.log";
  const std::string scene = jellyScene(ref.parent_path() / "jelly_1001.json", 1001, 4);
  ASSERT_EQ(runToEnd(args(scene, ref, {"--checkpoint-every", "2"}), log), 0) << readText(log);
  ASSERT_TRUE(fs::exists(ref / "checkpoint_1002.lsck"));
  ASSERT_TRUE(fs::exists(ref / "checkpoint_1004.lsck"));
  EXPECT_FALSE(fs::exists(ref / "checkpoint_1001.lsck"));
  // The directory as a run stopped after frame 1003 would leave it.
  for (const char* f : {"lodestone_run.json", "stats.json", "checkpoint_1002.lsck", "frame_1000.ply",
                        "frame_1001.ply", "frame_1002.ply"})
    fs::copy_file(ref / f, cut / f);
  ASSERT_EQ(runToEnd(args(scene, cut, {"--checkpoint-every", "2", "--resume"}), log), 0) << readText(log);
  EXPECT_NE(readText(log).find("checkpoint_1002.lsck: frame 1002"), std::string::npos) << readText(log);
  for (const char* n : {"1003", "1004"}) {
    ASSERT_TRUE(fs::exists(plyOf(cut, n))) << n;
    EXPECT_TRUE(readText(plyOf(ref, n)) == readText(plyOf(cut, n))) << "frame " << n << " differs";
  }
  EXPECT_TRUE(readText(ref / "checkpoint_1004.lsck") == readText(cut / "checkpoint_1004.lsck"));
  const std::string stats = readText(cut / "stats.json");
  for (const char* n : {"1001", "1002", "1003", "1004"})
    EXPECT_TRUE(std::regex_search(stats, std::regex(std::string("\"frame\":\\s*") + n))) << n << ": " << stats;
  fs::remove_all(ref.parent_path());
}

#if LODESTONE_TEST_HAVE_VDB
namespace {
// The grid names of a .vdb file, sorted.
std::vector<std::string> gridNames(const fs::path& path) {
  openvdb::initialize();
  openvdb::io::File file(path.string());
  file.open(false);
  std::vector<std::string> names;
  for (auto it = file.beginName(); it != file.endName(); ++it) names.push_back(it.gridName());
  file.close();
  std::sort(names.begin(), names.end());
  return names;
}

// The spike scene with every grid and the display aliases in output.vdb.
std::string allGridsScene(const fs::path& path) {
  return sceneVariant(path, "\"output\": {",
                      "\"output\": {\n    \"vdb\": [\"n\", \"phi\", \"H\", \"M\", \"B\", \"force\", \"mass\", "
                      "\"velocity\"], \"vdb_aliases\": true,");
}
}  // namespace

TEST(ExportFields, WritesTheSixFieldGridsItsHelpNamesAndRefusesAFrameBeyondTheScene) {
  const fs::path dir = scratch("export");
  const fs::path log = dir.parent_path() / "export.log";
  const std::string scene = allGridsScene(dir.parent_path() / "all_grids.json");
  const auto exportArgs = [&](const std::string& frameNumber) {
    return std::vector<std::string>{LODESTONE_CLI, "export-fields", scene, "--out", (dir / "f.vdb").string(),
                                    "--frame", frameNumber, "--dx", "0.02"};
  };
  ASSERT_EQ(runToEnd(exportArgs("1"), log), 0) << readText(log);
  EXPECT_EQ(gridNames(dir / "f.vdb"), (std::vector<std::string>{"B", "H", "M", "force", "n", "phi"}));
  // Frame 201 of a 200-frame scene: refused, not labelled as the last frame's state.
  EXPECT_EQ(runToEnd(exportArgs("201"), log), 1) << readText(log);
  EXPECT_NE(readText(log).find("--frame 201: the scene has 200 frames"), std::string::npos) << readText(log);
  fs::remove_all(dir.parent_path());
}

// export-fields --frame takes a scene frame number: frame 1001 of the spike
// scene from frame 1001 is one frame after the initial state, at t = 2.002 s.
TEST(ExportFields, TheFrameIsASceneFrameNumber) {
  const fs::path dir = scratch("export_start");
  const fs::path log = dir.parent_path() / "export_start.log";
  const std::string scene =
      sceneVariant(dir.parent_path() / "spike_1001.json", "\"frames\": 200,", "\"start_frame\": 1001, \"frames\": 200,");
  const auto exportArgs = [&](std::vector<std::string> extra) {
    std::vector<std::string> a{LODESTONE_CLI, "export-fields", scene, "--out", (dir / "f.vdb").string(), "--dx", "0.02"};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  ASSERT_EQ(runToEnd(exportArgs({"--frame", "1001"}), log), 0) << readText(log);
  EXPECT_NE(readText(log).find("(frame 1001, t = 2.002 s)"), std::string::npos) << readText(log);
  EXPECT_EQ(gridNames(dir / "f.vdb"), (std::vector<std::string>{"B", "H", "M", "force", "n", "phi"}));
  // Without --frame: the initial state, frame 1000 at t0 = 2 s.
  ASSERT_EQ(runToEnd(exportArgs({}), log), 0) << readText(log);
  EXPECT_NE(readText(log).find("(frame 1000, t = 2 s)"), std::string::npos) << readText(log);
  EXPECT_EQ(runToEnd(exportArgs({"--frame", "1201"}), log), 1) << readText(log);
  EXPECT_NE(readText(log).find("--frame 1201: the scene has 200 frames (1001..1200)"), std::string::npos)
      << readText(log);
  fs::remove_all(dir.parent_path());
}

TEST(RunOutput, TheInitialStateHasItsFieldFileToo) {
  const fs::path dir = scratch("fields0");
  const fs::path log = dir.parent_path() / "fields0.log";
  const std::string scene = allGridsScene(dir.parent_path() / "all_grids.json");
  ASSERT_EQ(runToEnd(args(scene, dir, {"--frames", "1:1", "--dx", "0.02", "--no-ply"}), log), 0) << readText(log);
  ASSERT_TRUE(fs::exists(dir / "fields_0000.vdb"));
  ASSERT_TRUE(fs::exists(dir / "fields_0001.vdb"));
  // The scene's eight grids and the display names density and vel, as for frame 1.
  EXPECT_EQ(gridNames(dir / "fields_0000.vdb"), (std::vector<std::string>{"B", "H", "M", "density", "force", "mass",
                                                                          "n", "phi", "vel", "velocity"}));
  EXPECT_EQ(gridNames(dir / "fields_0000.vdb"), gridNames(dir / "fields_0001.vdb"));
  fs::remove_all(dir.parent_path());
}
#endif
