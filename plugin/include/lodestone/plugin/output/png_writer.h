#pragma once
// A minimal PNG writer for the examples: 8-bit RGB, no interlace, every row
// stored with filter type 0 (None) and deflated by zlib. Enough for field
// slices and plots; not a general image library.
#include <cstdint>
#include <string>
#include <vector>

namespace lodestone::output {

/// Writes `width` x `height` pixels of 8-bit RGB (3 bytes per pixel, rows top
/// to bottom, left to right) to `path` as a PNG file, replacing any existing
/// file atomically (a temporary file renamed over it, atomic_file.h). Throws lodestone::Error naming `path` when the size is not 1..2^24
/// per side, `rgb` is null, or the file cannot be written.
void writePng(const std::string& path, int width, int height, const std::uint8_t* rgb);

/// The bytes of that PNG file (same rules; the error names `what`).
std::vector<std::uint8_t> encodePng(int width, int height, const std::uint8_t* rgb,
                                    const std::string& what = "PNG image");

}  // namespace lodestone::output
