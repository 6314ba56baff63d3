#include "vdb_atomic_write.h"

#include <atomic>
#include <filesystem>
#include <random>
#include <system_error>

#include "lodestone/core/base/error.h"

namespace lodestone::detail {

namespace {
std::string temporaryName(const std::filesystem::path& target) {
  static std::atomic<unsigned> counter{0};
  std::random_device rd;
  return target.string() + ".tmp-" + std::to_string(rd()) + "-" + std::to_string(counter++);
}
}  // namespace

void writeVdbAtomically(const std::string& path, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& meta) {
  const std::filesystem::path target(path);
  const std::string tmp = temporaryName(target);
  try {
    openvdb::io::File file(tmp);
    file.write(grids, meta);
    file.close();
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw InvalidArgument(concat("VDB file '", path, "': cannot write: ", e.what()));
  }
  std::error_code ec;
  std::filesystem::rename(tmp, target, ec);
  if (ec) {
    std::error_code ec2;
    std::filesystem::remove(tmp, ec2);
    throw InvalidArgument(concat("VDB file '", path, "': cannot rename the temporary file into place: ",
                                 ec.message()));
  }
}

}  // namespace lodestone::detail
