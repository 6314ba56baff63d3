#pragma once
// Atomic replacement of an output file: the bytes go to a temporary file in
// the same directory (so the rename cannot cross file systems), which is then
// renamed over the destination. Readers (a viewer polling the output folder,
// a crash half-way through a frame) therefore see either the old file or the
// complete new one, never a truncated file. No fsync: this protects readers,
// not against power loss.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace lodestone::output {

/// Writes `size` bytes to `path` atomically (see above), replacing any
/// existing file. On failure the temporary file is removed and
/// lodestone::Error is thrown naming `path` and the system's reason (missing
/// directory, permission, disk full...). `data` may be null when size is 0.
void writeFileAtomically(const std::string& path, const void* data, std::size_t size);

inline void writeFileAtomically(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  writeFileAtomically(path, bytes.data(), bytes.size());
}
inline void writeFileAtomically(const std::string& path, const std::string& text) {
  writeFileAtomically(path, text.data(), text.size());
}

}  // namespace lodestone::output
