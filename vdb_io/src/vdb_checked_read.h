#pragma once
// Internal to vdb_io: reads a whole .vdb file through a stream that throws
// on any short read. openvdb::io::File silently accepts some truncated
// files, its delayed loading maps the file (a later access to a truncated
// page would crash), and on some truncated point files it builds an error
// message from garbage lengths (gigabytes of memory before it throws).
// Every reader of a file a user hands us goes through here.
#include <string>

#include <openvdb/openvdb.h>

namespace lodestone::detail {

struct VdbFileContents {
  openvdb::GridPtrVecPtr grids;  ///< every grid, fully loaded
  openvdb::MetaMap::Ptr meta;    ///< the file's metadata
};

/// Reads `path` whole. Throws InvalidArgument starting with `where` for a
/// missing or irregular file and for one that is corrupt, truncated or not
/// a VDB file.
VdbFileContents readVdbChecked(const std::string& path, const std::string& where);

/// The grid named `name` in `contents`, or null; `names` gets the names of
/// all grids, comma-separated (for messages).
openvdb::GridBase::Ptr findGrid(const VdbFileContents& contents, const std::string& name, std::string& names);

}  // namespace lodestone::detail
