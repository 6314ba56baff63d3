#pragma once
// `lodestone run SCENE --out DIR`: simulates the scene and writes its frames,
// checkpoints, contact sheet and stats.json in DIR (docs/cli.md).
#include "command_args.h"

namespace lodestone::examples {

/// Returns the exit code (kExitBlownUp, kExitBrokenPipe, 128 + a stop
/// signal); throws lodestone::Error on a bad scene, directory or checkpoint.
int run(const Args& a);

}  // namespace lodestone::examples
