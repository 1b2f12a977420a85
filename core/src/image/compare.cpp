// Image comparison (compare.h): error metrics and a heat map of the differing pixels.
#include "rayfarm/compare.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>

namespace rayfarm {
namespace {

bool well_formed(const Image& image) {
  return image.width >= 0 && image.height >= 0 &&
         image.rgb.size() == static_cast<std::size_t>(image.width) * image.height * 3;
}

// A buffer that does not match its size counts as a size mismatch rather than a bad read.
bool same_size(const Image& a, const Image& b) {
  return a.width == b.width && a.height == b.height && well_formed(a) && well_formed(b);
}

const std::uint8_t* pixel(const Image& image, int x, int y) { return image.row(y) + x * 3; }

int max_channel_difference(const std::uint8_t* p, const std::uint8_t* q) {
  return std::max({std::abs(p[0] - q[0]), std::abs(p[1] - q[1]), std::abs(p[2] - q[2])});
}

// Whether pixel (x, y) of `from` is within the threshold of some pixel of the 3x3
// neighbourhood of (x, y) in `to`, clipped at the border.
bool matches_nearby(const Image& from, const Image& to, int x, int y, int threshold) {
  const std::uint8_t* p = pixel(from, x, y);
  for (int ny = std::max(y - 1, 0); ny <= std::min(y + 1, to.height - 1); ++ny) {
    for (int nx = std::max(x - 1, 0); nx <= std::min(x + 1, to.width - 1); ++nx) {
      if (max_channel_difference(p, pixel(to, nx, ny)) <= threshold) return true;
    }
  }
  return false;
}

// Both directions must match: otherwise a thin line missing from one image would be
// forgiven whenever its neighbours agree.
bool pixel_differs(const Image& a, const Image& b, int x, int y, const CompareOptions& options) {
  int threshold = std::clamp(options.threshold, 0, 255);
  if (max_channel_difference(pixel(a, x, y), pixel(b, x, y)) <= threshold) return false;
  if (!options.neighborhood) return true;
  return !matches_nearby(a, b, x, y, threshold) || !matches_nearby(b, a, x, y, threshold);
}

// Black, then blue, red and yellow as t goes from 0 to 1.
void heat_colour(double t, std::uint8_t* out) {
  constexpr double kStops[4][3] = {{0, 0, 0}, {0, 0, 255}, {255, 0, 0}, {255, 255, 0}};
  double scaled = std::clamp(t, 0.0, 1.0) * 3;
  int i = std::min(static_cast<int>(scaled), 2);
  double f = scaled - i;
  for (int c = 0; c < 3; ++c) {
    out[c] = static_cast<std::uint8_t>(
        std::lround(kStops[i][c] + (kStops[i + 1][c] - kStops[i][c]) * f));
  }
}

}  // namespace

std::optional<CompareResult> compare_images(const Image& a, const Image& b,
                                            const CompareOptions& options, std::string* error) {
  if (!same_size(a, b)) {
    if (error) {
      *error = "image sizes differ: " + std::to_string(a.width) + "x" + std::to_string(a.height) +
               " vs " + std::to_string(b.width) + "x" + std::to_string(b.height);
    }
    return std::nullopt;
  }
  CompareResult r;
  r.width = a.width;
  r.height = a.height;
  double sum_squares = 0;
  double sum_abs = 0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) {
    int d = std::abs(a.rgb[i] - b.rgb[i]);
    sum_squares += d * d;
    sum_abs += d;
    r.max_abs = std::max(r.max_abs, d);
    r.differing_channels += d != 0;
  }
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      if (max_channel_difference(pixel(a, x, y), pixel(b, x, y)) > 1) ++r.off_by_more_than_1;
      if (pixel_differs(a, b, x, y, options)) ++r.differing_pixels;
    }
  }
  std::size_t samples = a.rgb.size();
  long long pixels = static_cast<long long>(a.width) * a.height;
  r.rmse = samples ? std::sqrt(sum_squares / samples) : 0;
  r.mean_abs = samples ? sum_abs / samples : 0;
  r.psnr = r.rmse == 0 ? std::numeric_limits<double>::infinity() : 20 * std::log10(255 / r.rmse);
  r.differing_fraction = pixels ? static_cast<double>(r.differing_pixels) / pixels : 0;
  return r;
}

Image diff_image(const Image& a, const Image& b, const CompareOptions& options) {
  if (!same_size(a, b)) return Image();
  Image out(a.width, a.height);
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      int d = max_channel_difference(pixel(a, x, y), pixel(b, x, y));
      if (d == 0) continue;
      // Tolerated differences stay in the dim blue band, differing pixels start at purple, so
      // the map shows what counted; the square root lifts small differences out of the dark.
      double t = std::sqrt(d / 255.0);
      t = pixel_differs(a, b, x, y, options) ? 0.5 + 0.5 * t : t / 3;
      heat_colour(t, out.row(y) + x * 3);
    }
  }
  return out;
}

nlohmann::json compare_json(const CompareResult& r, const CompareOptions& options) {
  using Json = nlohmann::json;
  return {{"width", r.width},
          {"height", r.height},
          {"rmse", r.rmse},
          {"psnr", std::isinf(r.psnr) ? Json(nullptr) : Json(r.psnr)},
          {"identical", r.max_abs == 0},
          {"max_abs", r.max_abs},
          {"mean_abs", r.mean_abs},
          {"differing_pixels", r.differing_pixels},
          {"differing_channels", r.differing_channels},
          {"differing_fraction", r.differing_fraction},
          {"off_by_more_than_1", r.off_by_more_than_1},
          {"threshold", options.threshold},
          {"neighborhood", options.neighborhood}};
}

}  // namespace rayfarm
