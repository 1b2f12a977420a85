// The cpsc102 profile's way of turning a tile of pixels into colours: the reference
// program's camera (x87.h) and, with spp > 1, its anti-aliasing: spp jittered samples per
// pixel drawn from glibc's random() in the program's order (bottom row first, left to right,
// x then y), summed in its arithmetic. The stream runs across the whole image, so its state
// is kept at every tile's row starts, and all of a pixel's samples are taken in one pass.
#pragma once

#include <array>
#include <vector>

#include <glm/vec3.hpp>

#include "render/cpsc102/glibc_random.h"
#include "render/cpsc102/reference_tracer.h"
#include "render/tile_grid.h"

namespace rayfarm::cpsc102 {

class ReferencePipeline {
 public:
  explicit ReferencePipeline(RefScene scene) : s_(std::move(scene)), grid_(s_.width, s_.height) {
    if (s_.spp <= 1) return;
    // One run through the stream: the state where each tile's part of each row begins.
    GlibcRandom random(s_.seed);
    starts_.reserve(static_cast<size_t>(s_.height) * grid_.tiles_x);
    for (int y = 0; y < s_.height; ++y)
      for (int tx = 0; tx < grid_.tiles_x; ++tx) {
        starts_.push_back(random);
        const int x0 = tx * kTileSize, x1 = std::min(x0 + kTileSize, s_.width);
        random.discard(2ull * s_.spp * (x1 - x0));
      }
  }

  int width() const { return s_.width; }
  int height() const { return s_.height; }
  int spp() const { return s_.spp; }
  int samples_per_pass() const { return s_.spp; }
  std::vector<std::string> parts() const {
    std::vector<std::string> out{"primary", "reference"};
    if (s_.spp > 1) out.push_back("supersampling");
    if (!s_.bvh.empty()) out.push_back("bvh");
    return out;
  }

  // The colours of a tile (rows top to bottom), each the mean of the pixel's samples;
  // `error` gets the sum over its channels of the squared standard error of those means.
  template <class Canceled>
  bool render_tile(const TileBounds& b, int /*pass*/, std::vector<glm::dvec3>& out,
                   RayCounts& counts, double& error, Canceled&& canceled) const {
    out.resize(static_cast<size_t>(b.width()) * b.rows());
    ReferenceTracer<> tracer(s_);
    error = 0;
    for (int r = b.r0; r < b.r1; ++r) {
      if (canceled()) return false;
      const int y = s_.height - 1 - r;  // world row y = 0 is the bottom of the image
      glm::dvec3* px = out.data() + static_cast<size_t>(r - b.r0) * b.width();
      if (s_.spp <= 1) {
        for (int x = b.x0; x < b.x1; ++x) {
          const V3 c = tracer.primary(screen_x(x), screen_y(y));
          *px++ = {c.x, c.y, c.z};
        }
        continue;
      }
      GlibcRandom random = starts_[static_cast<size_t>(y) * grid_.tiles_x + b.x0 / kTileSize];
      for (int x = b.x0; x < b.x1; ++x) {
        V3 acc;
        double sum_sq[3] = {};
        for (int k = 0; k < s_.spp; ++k) {
          const std::array<double, 2> w = jittered_point(random, x, y);
          const V3 c = tracer.primary(w[0], w[1]);
          acc = add(acc, c);
          for (int i = 0; i < 3; ++i) sum_sq[i] += c[i] * c[i];
        }
        const V3 value = mean_of(acc);
        *px++ = {value.x, value.y, value.z};
        const double n = s_.spp;
        for (int i = 0; i < 3; ++i) {
          const double mean = acc[i] / n;
          const double var = (sum_sq[i] - acc[i] * mean) / (n - 1);
          error += (var > 0 ? var : 0) / n;
        }
      }
    }
    counts = tracer.counts;
    return true;
  }

  const RefScene& scene() const { return s_; }

  // The screen points of pixel (x, image row r)'s samples, in the order render_tile takes
  // them: with one sample the pixel's own point, else its jittered points, the stream
  // taken up where this pixel's part of it begins.
  std::vector<std::array<double, 2>> sample_points(int x, int r) const {
    const int y = s_.height - 1 - r;
    if (s_.spp <= 1) return {{screen_x(x), screen_y(y)}};
    const int x0 = x / kTileSize * kTileSize;
    GlibcRandom random = starts_[static_cast<size_t>(y) * grid_.tiles_x + x / kTileSize];
    random.discard(2ull * s_.spp * (x - x0));
    std::vector<std::array<double, 2>> out;
    for (int k = 0; k < s_.spp; ++k) out.push_back(jittered_point(random, x, y));
    return out;
  }

  // A supersampled pixel's value from the sum of its samples, in the program's arithmetic.
  V3 mean_of(const V3& sum) const {
    const double inv = R(1.0L / s_.spp);
    return {R(static_cast<X>(sum.x) * inv), R(static_cast<X>(sum.y) * inv),
            R(static_cast<X>(sum.z) * inv)};
  }

 private:
  // The next sample's screen point of pixel (x, world row y).
  std::array<double, 2> jittered_point(GlibcRandom& random, int x, int y) const {
    const double fx = R(x + static_cast<X>(jitter(random)));
    const double fy = R(y + static_cast<X>(jitter(random)));
    return {screen_x(fx), screen_y(fy)};
  }

  // random() / (2^31 − 1) − 0.5, as the program computed it.
  static double jitter(GlibcRandom& random) {
    return R(static_cast<X>(R(random.next() / 2147483647.0L)) - 0.5L);
  }
  // The program's camera: x/(W−1)·ww (a one-pixel side looks through the middle).
  double screen_x(double x) const {
    if (s_.width == 1) return R((static_cast<X>(x) + 0.5L) * s_.world_width);
    return R(static_cast<X>(x) / (s_.width - 1) * s_.world_width);
  }
  double screen_y(double y) const {
    if (s_.height == 1) return R((static_cast<X>(y) + 0.5L) * s_.world_height);
    return R(static_cast<X>(y) / (s_.height - 1) * s_.world_height);
  }

  RefScene s_;
  TileGrid grid_;
  std::vector<GlibcRandom> starts_;  // per world row and tile column
};

}  // namespace rayfarm::cpsc102
