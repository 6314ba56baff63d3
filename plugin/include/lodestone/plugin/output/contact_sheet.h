#pragma once
// A contact sheet: a run's frame previews as thumbnails in a grid, row by
// row in frame order (contact_sheet.png of `lodestone run`).
#include <vector>

#include "lodestone/plugin/output/colormap.h"

namespace lodestone::output {

/// `image` scaled to `width` pixels (>= 1, at most the image's width; the
/// height keeps the aspect ratio, at least 1) by averaging the source
/// pixels each thumbnail pixel covers. Throws InvalidArgument on an empty
/// image or a bad width.
RgbImage thumbnail(const RgbImage& image, int width);

/// The thumbnails (all of one size, else InvalidArgument) in rows of
/// `columns` (>= 1), `gap` pixels (>= 0) apart and around, on `background`.
RgbImage contactSheet(const std::vector<RgbImage>& thumbnails, int columns, int gap = 4, Rgb background = {30, 32, 38});

/// Which of `count` frames a sheet of at most `maxThumbnails` shows: every
/// stride-th from the first, stride = ceil(count / maxThumbnails).
int contactSheetStride(int count, int maxThumbnails);

}  // namespace lodestone::output
