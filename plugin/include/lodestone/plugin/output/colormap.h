#pragma once
// Perceptual colour maps and a small renderer for 2D scalar slices: value ->
// colour (linear or log scale, bilinear upsampling), a contour overlay (e.g.
// the material outline where the density crosses half its bulk value) and a
// horizontal colour-bar strip. No text: callers report the value range
// (ColourRange) in their console or JSON output instead.
#include <cstdint>
#include <limits>
#include <vector>

namespace lodestone::output {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};

enum class Colormap {
  Viridis,  ///< dark blue -> green -> yellow (matplotlib's default)
  Inferno   ///< black -> purple -> orange -> pale yellow
};
const char* toString(Colormap map);

/// Colour of t in [0, 1] (clamped); NaN maps to mid grey. Degree-6 polynomial
/// fits of matplotlib's maps (Matt Zucker, CC0), within ~1% of the tables.
Rgb mapColour(Colormap map, double t);

/// Values on a regular 2D lattice, x (column) fastest, row 0 at the bottom,
/// so that a slice of a z-up grid keeps z pointing up in the image.
struct ScalarSlice {
  int width = 0, height = 0;
  std::vector<double> values;

  ScalarSlice() = default;
  /// Throws lodestone::Error unless both sides are >= 1.
  ScalarSlice(int width, int height, double value = 0.0);
  double& at(int i, int j) { return values[std::size_t(i) + std::size_t(width) * std::size_t(j)]; }
  double at(int i, int j) const { return values[std::size_t(i) + std::size_t(width) * std::size_t(j)]; }
  /// Bilinear interpolation at lattice coordinates (u, v), clamped to the lattice.
  double sample(double u, double v) const;
};

/// 8-bit RGB pixels, row 0 at the top (as writePng expects).
struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< 3 bytes per pixel

  RgbImage() = default;
  RgbImage(int width, int height, Rgb fill = {});
  void set(int x, int y, Rgb c);
  Rgb get(int x, int y) const;
};

struct RenderOptions {
  Colormap colormap = Colormap::Viridis;
  bool logScale = false;
  /// Value at the bottom of the colour scale; NaN: automatic (smallest finite
  /// value, or for log scale max * 10^-logDecades unless the smallest
  /// positive value is larger).
  double minValue = std::numeric_limits<double>::quiet_NaN();
  /// Value at the top of the colour scale; NaN: the largest finite value.
  double maxValue = std::numeric_limits<double>::quiet_NaN();
  double logDecades = 4;    ///< decades shown by an automatic log range (> 0)
  int pixelsPerSample = 1;  ///< upsampling (bilinear): image side = (samples - 1) * p + 1
};

/// The values mapped to the two ends of the colour scale.
struct ColourRange {
  double min = 0, max = 0;
  bool log = false;
  /// Position of `value` on the scale, clamped to [0, 1]; NaN stays NaN.
  double normalise(double value) const;
};

/// Renders `slice` (at least 1 x 1) into an image of ((width - 1) p + 1) x
/// ((height - 1) p + 1) pixels, pixel (x, y) showing lattice point
/// (x / p, height - 1 - y / p). Non-finite values are drawn grey. Writes the
/// range used to `range` when given. Throws lodestone::Error on bad options.
RgbImage renderScalar(const ScalarSlice& slice, const RenderOptions& options, ColourRange* range = nullptr);

/// Overlays the contour where `field` (a lattice rendered with the same
/// pixelsPerSample, so covering the top rows of `image`) crosses `level`:
/// pixels at or above the level with a 4-neighbour below it are painted.
void drawContour(RgbImage& image, const ScalarSlice& field, int pixelsPerSample, double level, Rgb colour);

/// Appends `gap` rows of `background` and a `height`-pixel colour bar under
/// the image, running from the bottom of the scale (left) to the top (right).
/// For a log range, a short dark tick marks each power of ten.
void appendColourBar(RgbImage& image, Colormap map, const ColourRange& range, int height = 16, int gap = 4,
                     Rgb background = {});

}  // namespace lodestone::output
