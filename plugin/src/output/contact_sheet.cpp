#include "lodestone/plugin/output/contact_sheet.h"

#include <algorithm>
#include <cmath>

#include "lodestone/core/base/error.h"

namespace lodestone::output {

RgbImage thumbnail(const RgbImage& image, int width) {
  require(image.width > 0 && image.height > 0, "thumbnail: the image is empty");
  require(width >= 1 && width <= image.width, "thumbnail: width must be in [1, ", image.width, "] pixels, got ", width);
  const int height = std::max(1, int(std::lround(double(image.height) * width / image.width)));
  RgbImage out(width, height);
  const double sx = double(image.width) / width, sy = double(image.height) / height;
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      const int x0 = int(i * sx), x1 = std::max(x0 + 1, int((i + 1) * sx));
      const int y0 = int(j * sy), y1 = std::max(y0 + 1, int((j + 1) * sy));
      double r = 0, g = 0, b = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const Rgb c = image.get(x, y);
          r += c.r, g += c.g, b += c.b;
        }
      const double n = double(x1 - x0) * (y1 - y0);
      out.set(i, j, {std::uint8_t(std::lround(r / n)), std::uint8_t(std::lround(g / n)), std::uint8_t(std::lround(b / n))});
    }
  return out;
}

RgbImage contactSheet(const std::vector<RgbImage>& thumbnails, int columns, int gap, Rgb background) {
  require(columns >= 1, "contact sheet: columns must be >= 1, got ", columns);
  require(gap >= 0, "contact sheet: gap must be >= 0 pixels, got ", gap);
  require(!thumbnails.empty(), "contact sheet: no thumbnails");
  const int w = thumbnails[0].width, h = thumbnails[0].height;
  for (std::size_t n = 0; n < thumbnails.size(); ++n)
    require(thumbnails[n].width == w && thumbnails[n].height == h, "contact sheet: thumbnail ", n, " is ",
            thumbnails[n].width, " x ", thumbnails[n].height, " pixels, the first ", w, " x ", h);
  const int count = int(thumbnails.size());
  const int cols = std::min(columns, count), rows = (count + cols - 1) / cols;
  RgbImage sheet(gap + cols * (w + gap), gap + rows * (h + gap), background);
  for (int n = 0; n < count; ++n) {
    const int x0 = gap + (n % cols) * (w + gap), y0 = gap + (n / cols) * (h + gap);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) sheet.set(x0 + x, y0 + y, thumbnails[std::size_t(n)].get(x, y));
  }
  return sheet;
}

int contactSheetStride(int count, int maxThumbnails) {
  require(maxThumbnails >= 1, "contact sheet: maxThumbnails must be >= 1, got ", maxThumbnails);
  return count <= maxThumbnails ? 1 : (count + maxThumbnails - 1) / maxThumbnails;
}

}  // namespace lodestone::output
