#pragma once
// Internal to vdb_io: writes grids and file metadata to a .vdb atomically (a
// temporary file in the target's directory, then rename), so a reader never
// sees a half-written file. Throws InvalidArgument naming `path`; on failure
// the target is untouched and the temporary removed.
#include <string>

#include <openvdb/openvdb.h>

namespace lodestone::detail {

void writeVdbAtomically(const std::string& path, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& meta);

}  // namespace lodestone::detail
