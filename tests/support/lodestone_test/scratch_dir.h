#pragma once
// Scratch directories of the tests that write files: one per test process
// (its pid) under the system's temporary directory.
#include <unistd.h>

#include <filesystem>
#include <string>

namespace lodestone::test {

/// TMP/lodestone_<prefix>_<pid>/<name>, emptied and created.
inline std::filesystem::path scratchDir(const std::string& prefix, const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("lodestone_" + prefix + "_" + std::to_string(::getpid())) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace lodestone::test
