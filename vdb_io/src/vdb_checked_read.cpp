// Whole-file VDB reading that fails cleanly on bad files. See vdb_checked_read.h.
#include "vdb_checked_read.h"

#include <exception>
#include <filesystem>
#include <fstream>

#include <openvdb/io/Stream.h>

#include "lodestone/core/base/error.h"
#include "lodestone/vdb_io/grid_conversion.h"

namespace lodestone::detail {

VdbFileContents readVdbChecked(const std::string& path, const std::string& where) {
  initializeVdb();
  std::error_code ec;
  require(std::filesystem::is_regular_file(path, ec), where, ": file not found or not a regular file");
  VdbFileContents out;
  try {
    std::ifstream in;
    in.exceptions(std::ios::badbit | std::ios::failbit);
    in.open(path, std::ios::in | std::ios::binary);
    openvdb::io::Stream stream(in, /*delayLoad=*/false);
    out.grids = stream.getGrids();
    out.meta = stream.getMetadata();
  } catch (const std::exception& e) {
    throw InvalidArgument(concat(where, ": cannot read (corrupt, truncated or not a VDB file): ", e.what()));
  }
  require(out.grids != nullptr, where, ": cannot read");
  if (!out.meta) out.meta = std::make_shared<openvdb::MetaMap>();
  return out;
}

openvdb::GridBase::Ptr findGrid(const VdbFileContents& contents, const std::string& name, std::string& names) {
  openvdb::GridBase::Ptr found;
  names.clear();
  for (const auto& g : *contents.grids) {
    if (!g) continue;
    if (g->getName() == name && !found) found = g;
    names += (names.empty() ? "" : ", ") + g->getName();
  }
  return found;
}

}  // namespace lodestone::detail
