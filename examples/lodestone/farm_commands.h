#pragma once
// The farm commands of `lodestone` (docs/farm.md, docs/cli.md):
//   wedge SCENE --vary KEY=V1,V2,... --out DIR   variants of a scene, run
//                                                locally or as a Slurm array
//   wedge-summary DIR                            contact sheet and table
//   farm-post DIR --task T                       per-frame post-processing of
//                                                a run's cache over frame ranges
// command_args.cpp registers them (addFarmCommands); main.cpp runs the one
// chosen.
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace lodestone::examples {

struct FarmArgs {
  std::string scene, dir;
  std::vector<std::string> vary;
  int local = 0;  // processes at a time (0: not local)
  bool slurm = false, wait = false, dryRun = false, here = false;
  std::string partition;
  std::vector<std::string> sbatchArgs;
  int first = 0, last = 0;
  bool framesGiven = false;
  int checkpointEvery = 1;
  int threads = 0;
  std::string task = "export-fields";
  int framesPerTask = 10;
  std::string postScene;  // farm-post: the scene (default: the run manifest's)
  std::vector<std::string> args;  // the command line as given
};

/// Declares wedge, wedge-summary and farm-post on `app`, filling `a`.
/// `readFrameRange` parses "A:B" (the run command's rule).
void addFarmCommands(CLI::App& app, FarmArgs& a);

/// Runs `command` when it is one of the farm commands (its exit code),
/// nullopt otherwise.
std::optional<int> runFarmCommand(const std::string& command, FarmArgs& a);

}  // namespace lodestone::examples
