#pragma once
// Reads the PNG files png_writer.h writes (8-bit RGB, no interlace), for
// programs that combine previews (the wedge contact sheet). Any of the five
// row filters is accepted; other colour types, bit depths and interlaced
// files are refused. Not a general image library.
#include <string>

#include "lodestone/plugin/output/colormap.h"

namespace lodestone::output {

/// The image in `path`. Throws lodestone::InvalidArgument naming the file
/// when it cannot be read, is not a PNG file, is damaged (CRC, zlib, size)
/// or is not 8-bit RGB without interlace.
RgbImage readPng(const std::string& path);

}  // namespace lodestone::output
