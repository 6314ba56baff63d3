// Atomic file replacement: content written, an existing file replaced (its
// permissions kept), no temporary left behind on success or failure, errors
// naming the path.
#include <gtest/gtest.h>
#include <unistd.h>

#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "lodestone/plugin/output/atomic_file.h"
#include "lodestone/core/base/error.h"

using namespace lodestone;
using namespace lodestone::output;

namespace {

std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::filesystem::path freshDir(const std::string& name) {
  // The process id keeps concurrent runs (several build trees) apart.
  const auto dir = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::size_t entries(const std::filesystem::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

}  // namespace

TEST(AtomicFile, WritesAndReplaces) {
  const auto dir = freshDir("lodestone_test_atomic_file");
  const auto path = dir / "stats.json";
  writeFileAtomically(path.string(), std::string("first version, longer\n"));
  EXPECT_EQ(readText(path), "first version, longer\n");
  ASSERT_EQ(::chmod(path.c_str(), 0640), 0);
  writeFileAtomically(path.string(), std::string("second\n"));
  EXPECT_EQ(readText(path), "second\n");
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
  writeFileAtomically(path.string(), nullptr, 0);
  EXPECT_EQ(readText(path), "");
  EXPECT_EQ(entries(dir), 1u);  // no temporary left
  std::filesystem::remove_all(dir);
}

TEST(AtomicFile, ErrorsNameThePathAndLeaveNothing) {
  const auto dir = freshDir("lodestone_test_atomic_file_errors");
  const std::string missing = (dir / "missing" / "a.txt").string();
  try {
    writeFileAtomically(missing, std::string("x"));
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  // The target is an existing directory: rename fails, the temporary is removed.
  std::filesystem::create_directories(dir / "sub");
  EXPECT_THROW(writeFileAtomically((dir / "sub").string(), std::string("x")), Error);
  EXPECT_EQ(entries(dir), 1u);
  EXPECT_THROW(writeFileAtomically("", std::string("x")), Error);
  std::filesystem::remove_all(dir);
}
