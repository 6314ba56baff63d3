#pragma once
// The command line of `lodestone`: what its commands and options set, the
// parser that declares them, and the exit codes (docs/cli.md).
#include <optional>
#include <string>
#include <vector>

#include "farm_commands.h"
#include "lodestone/plugin/scene.h"
#include "surface_command.h"

namespace lodestone::examples {

struct Args {
  std::string command, scene, out;
  int first = 0, last = 0;  // run --frames A:B, scene frame numbers
  bool framesGiven = false;  // run: --frames given (else all the scene's frames)
  plugin::SceneOptions options;
  int threads = 0;
  int ranks = 0;             // run: --ranks N (0: as launched)
  int frame = 0;            // export-fields: scene frame number
  bool frameGiven = false;  // export-fields: --frame given (else the initial state)
  std::string density, densityGrid = "n";  // export-fields: n (1/m^3) from a .vdb instead of the particles
  std::string particles;     // export-fields: the particles of a cache file instead of a simulated state
  bool png = true, ply = true;
  std::string outputs;        // run: --outputs LIST ("" = the scene's choice)
  SurfaceCommandArgs surface; // surface DIR
  int checkpointEvery = -1;  // -1: the scene's output.checkpoint_every
  bool resume = false, checkFinite = false;
  bool clean = false;         // run: delete another run's output in --out first
  int keepCheckpoints = 0;    // run: checkpoints kept (0 = all)
  double maxLost = 0.01;      // run: fraction of the particles that may be lost as non-finite
  long long maxSubsteps = 100000;  // run, export-fields: substeps per frame refused beyond
  bool markdown = false;      // nodes
  FarmArgs farm;              // wedge, wedge-summary, farm-post
  std::vector<std::string> args;  // the command line as given
};

// Exit codes (docs/cli.md).
inline constexpr int kExitError = 1;       // bad arguments, scene, directory or checkpoint; I/O failure
inline constexpr int kExitBlownUp = 3;     // more particles lost as non-finite than --max-lost allows
inline constexpr int kExitBrokenPipe = 141;  // standard output closed (128 + SIGPIPE)

/// Throws InvalidArgument with `message` and a pointer to --help.
[[noreturn]] void usageError(const std::string& message);

/// The commands and their options, declared once: the help text is generated
/// from these declarations. Fills `a`; returns the code to exit with after
/// --help, --version or a bad argument (message on stderr), nullopt to go on.
std::optional<int> parseArgs(int argc, char** argv, Args& a);

}  // namespace lodestone::examples
