#include "lodestone/plugin/output/colormap.h"

#include <algorithm>
#include <cmath>

#include "lodestone/core/base/error.h"

namespace lodestone::output {
namespace {

struct Poly6 {
  double c[7][3];
};

// Polynomial fits of matplotlib's viridis and inferno by Matt Zucker
// (https://www.shadertoy.com/view/WlfXRN, CC0): colour = sum_k c_k t^k.
constexpr Poly6 kViridis = {{{0.2777273272234177, 0.005407344544966578, 0.3340998053353061},
                             {0.1050930431085774, 1.404613529898575, 1.384590162594685},
                             {-0.3308618287255563, 0.214847559468213, 0.09509516302823659},
                             {-4.634230498983486, -5.799100973351585, -19.33244095627987},
                             {6.228269936347081, 14.17993336680509, 56.69055260068105},
                             {4.776384997670288, -13.74514537774601, -65.35303263337234},
                             {-5.435455855934631, 4.645852612178535, 26.3124352495832}}};
constexpr Poly6 kInferno = {{{0.0002189403691192265, 0.001651004631001012, -0.01948089843709184},
                             {0.1065134194856116, 0.5639564367884091, 3.932712388889277},
                             {11.60249308247187, -3.972853965665698, -15.9423941062914},
                             {-41.70399613139459, 17.43639888205313, 44.35414519872813},
                             {77.162935699427, -33.40235894210092, -81.80730925738993},
                             {-71.31942824499214, 32.62606426397723, 73.20951985803202},
                             {25.13112622477341, -12.24266895238567, -23.07032500287172}}};

std::uint8_t toByte(double v) { return std::uint8_t(std::lround(255.0 * std::clamp(v, 0.0, 1.0))); }

constexpr Rgb kGrey{128, 128, 128};

}  // namespace

const char* toString(Colormap map) { return map == Colormap::Inferno ? "inferno" : "viridis"; }

Rgb mapColour(Colormap map, double t) {
  if (std::isnan(t)) return kGrey;
  t = std::clamp(t, 0.0, 1.0);
  const Poly6& p = map == Colormap::Inferno ? kInferno : kViridis;
  double c[3];
  for (int ch = 0; ch < 3; ++ch) {
    double v = p.c[6][ch];
    for (int k = 5; k >= 0; --k) v = p.c[k][ch] + t * v;
    c[ch] = v;
  }
  return {toByte(c[0]), toByte(c[1]), toByte(c[2])};
}

ScalarSlice::ScalarSlice(int w, int h, double value) : width(w), height(h) {
  if (w < 1 || h < 1) throw Error(concat("scalar slice: size must be at least 1 x 1, got ", w, " x ", h));
  values.assign(std::size_t(w) * std::size_t(h), value);
}

double ScalarSlice::sample(double u, double v) const {
  u = std::clamp(u, 0.0, double(width - 1));
  v = std::clamp(v, 0.0, double(height - 1));
  const int i0 = std::min(int(u), std::max(width - 2, 0));
  const int j0 = std::min(int(v), std::max(height - 2, 0));
  const int i1 = std::min(i0 + 1, width - 1);
  const int j1 = std::min(j0 + 1, height - 1);
  const double fu = u - i0, fv = v - j0;
  const double a = at(i0, j0) + fu * (at(i1, j0) - at(i0, j0));
  const double b = at(i0, j1) + fu * (at(i1, j1) - at(i0, j1));
  return a + fv * (b - a);
}

RgbImage::RgbImage(int w, int h, Rgb fill) : width(w), height(h) {
  if (w < 1 || h < 1) throw Error(concat("image: size must be at least 1 x 1, got ", w, " x ", h));
  rgb.resize(3 * std::size_t(w) * std::size_t(h));
  for (std::size_t p = 0; p < rgb.size(); p += 3) {
    rgb[p] = fill.r;
    rgb[p + 1] = fill.g;
    rgb[p + 2] = fill.b;
  }
}

void RgbImage::set(int x, int y, Rgb c) {
  const std::size_t p = 3 * (std::size_t(x) + std::size_t(width) * std::size_t(y));
  rgb[p] = c.r;
  rgb[p + 1] = c.g;
  rgb[p + 2] = c.b;
}

Rgb RgbImage::get(int x, int y) const {
  const std::size_t p = 3 * (std::size_t(x) + std::size_t(width) * std::size_t(y));
  return {rgb[p], rgb[p + 1], rgb[p + 2]};
}

double ColourRange::normalise(double value) const {
  if (std::isnan(value)) return value;
  double t;
  if (log) {
    const double lo = std::log10(min), hi = std::log10(max);
    t = hi > lo ? (std::log10(std::max(value, min)) - lo) / (hi - lo) : 0.0;
  } else {
    t = max > min ? (value - min) / (max - min) : 0.0;
  }
  return std::clamp(t, 0.0, 1.0);
}

RgbImage renderScalar(const ScalarSlice& slice, const RenderOptions& options, ColourRange* rangeOut) {
  if (slice.width < 1 || slice.height < 1 || slice.values.size() != std::size_t(slice.width) * slice.height)
    throw Error(concat("render: slice of ", slice.width, " x ", slice.height, " samples holds ",
                       slice.values.size(), " values"));
  const int p = options.pixelsPerSample;
  if (p < 1 || p > 64) throw Error(concat("render: pixelsPerSample must be in 1..64, got ", p));
  if (options.logScale && !(options.logDecades > 0 && std::isfinite(options.logDecades)))
    throw Error(concat("render: logDecades must be positive, got ", options.logDecades));

  // Range: explicit ends win; otherwise from the finite (for log: positive) values.
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, loPositive = lo;
  for (double v : slice.values) {
    if (!std::isfinite(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    if (v > 0) loPositive = std::min(loPositive, v);
  }
  ColourRange range;
  range.log = options.logScale;
  range.max = std::isnan(options.maxValue) ? hi : options.maxValue;
  if (!std::isnan(options.minValue)) {
    range.min = options.minValue;
  } else if (options.logScale) {
    range.min = std::max(loPositive, range.max * std::pow(10.0, -options.logDecades));
  } else {
    range.min = lo;
  }
  if (!std::isfinite(range.max)) range.max = range.log ? 1.0 : 0.0;  // no finite values at all
  if (!std::isfinite(range.min) || range.min > range.max) range.min = range.max;
  if (range.log && !(range.min > 0)) {
    if (!(range.max > 0)) range.max = 1.0;
    range.min = std::min(range.max, range.max * std::pow(10.0, -options.logDecades));
  }
  if (rangeOut) *rangeOut = range;

  const int W = (slice.width - 1) * p + 1, H = (slice.height - 1) * p + 1;
  RgbImage image(W, H);
  for (int y = 0; y < H; ++y) {
    const double v = double(H - 1 - y) / p;
    for (int x = 0; x < W; ++x) {
      const double value = slice.sample(double(x) / p, v);
      image.set(x, y, std::isfinite(value) ? mapColour(options.colormap, range.normalise(value)) : kGrey);
    }
  }
  return image;
}

void drawContour(RgbImage& image, const ScalarSlice& field, int p, double level, Rgb colour) {
  if (p < 1) throw Error(concat("contour: pixelsPerSample must be >= 1, got ", p));
  const int W = std::min(image.width, (field.width - 1) * p + 1);
  const int H = std::min(image.height, (field.height - 1) * p + 1);
  if (W < 1 || H < 1) return;
  std::vector<signed char> above(std::size_t(W) * H);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      above[std::size_t(x) + std::size_t(W) * y] = field.sample(double(x) / p, double(H - 1 - y) / p) >= level;
  auto isAbove = [&](int x, int y) { return above[std::size_t(x) + std::size_t(W) * y] != 0; };
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      if (!isAbove(x, y)) continue;
      const bool edge = (x > 0 && !isAbove(x - 1, y)) || (x + 1 < W && !isAbove(x + 1, y)) ||
                        (y > 0 && !isAbove(x, y - 1)) || (y + 1 < H && !isAbove(x, y + 1));
      if (edge) image.set(x, y, colour);
    }
}

void appendColourBar(RgbImage& image, Colormap map, const ColourRange& range, int height, int gap, Rgb background) {
  if (height < 1 || gap < 0) throw Error(concat("colour bar: height must be >= 1 and gap >= 0, got ", height, ", ", gap));
  if (image.width < 1) throw Error("colour bar: the image is empty");
  const int top = image.height + gap;
  image.height = top + height;
  image.rgb.resize(3 * std::size_t(image.width) * std::size_t(image.height));
  for (int y = top - gap; y < top; ++y)
    for (int x = 0; x < image.width; ++x) image.set(x, y, background);
  const int W = image.width;
  for (int x = 0; x < W; ++x) {
    const Rgb c = mapColour(map, W > 1 ? double(x) / (W - 1) : 0.5);
    for (int y = top; y < top + height; ++y) image.set(x, y, c);
  }
  if (range.log && range.max > range.min && W > 1) {
    const Rgb tick{20, 20, 20};
    const double lo = std::log10(range.min), hi = std::log10(range.max);
    for (double d = std::ceil(lo); d <= hi; d += 1.0) {
      const int x = int(std::lround((d - lo) / (hi - lo) * (W - 1)));
      for (int y = top; y < top + std::max(1, height / 3); ++y) image.set(x, y, tick);
    }
  }
}

}  // namespace lodestone::output
