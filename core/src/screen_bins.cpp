// Screen bin construction: each widened sphere's box is projected through the eye onto the
// screen plane (exact bounds: over a box in front of the eye, the projection is extreme at
// its corners), turned into a padded pixel rectangle and entered in every tile it reaches.
#include "screen_bins.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>

namespace rayfarm {
namespace {

struct Rect {
  int x0, x1, r0, r1;
};

// The pixel range [lo, hi] (inclusive, clipped to [0, count - 1]) whose screen coordinate
// can fall in [smin, smax] (world units along an axis of length `world`); false if none.
bool pixel_range(double smin, double smax, double world, int count, double pad, int& lo,
                 int& hi) {
  if (count == 1) {  // the one pixel looks through the middle, whatever the projection
    lo = hi = 0;
    return true;
  }
  const double scale = (count - 1) / world;
  double a = smin * scale, b = smax * scale;
  // Rounding of the projection itself, relative to its magnitude.
  a -= pad + 1e-9 * (std::abs(a) + 1);
  b += pad + 1e-9 * (std::abs(b) + 1);
  if (!(b >= 0) || !(a <= count - 1)) return false;
  lo = static_cast<int>(std::floor(std::max(a, 0.0)));
  hi = static_cast<int>(std::ceil(std::min(b, count - 1.0)));
  return true;
}

// The rectangle of pixels whose primary rays can meet the sphere; false if no ray can.
bool sphere_rect(const ScreenCamera& cam, const WidenedSphere& s, Rect& out) {
  const glm::dvec3& e = cam.eye;
  const glm::dvec3 lo = s.centre - s.radius, hi = s.centre + s.radius;
  // Along a primary ray, w = (ez - z) / ez runs from 0 at the eye to 1 on the screen.
  const double w_lo = (e.z - lo.z) / e.z, w_hi = (e.z - hi.z) / e.z;
  const double w_min = std::min(w_lo, w_hi), w_max = std::max(w_lo, w_hi);
  if (!(w_max > 0)) return false;  // wholly behind the eye
  if (!(w_min > 0)) {              // around the eye's plane: any ray may meet it
    out = {0, cam.width - 1, 0, cam.height - 1};
    return true;
  }
  double sx[2] = {INFINITY, -INFINITY}, sy[2] = {INFINITY, -INFINITY};
  for (double w : {w_lo, w_hi}) {
    for (double x : {lo.x, hi.x}) {
      const double v = e.x + (x - e.x) / w;
      sx[0] = std::min(sx[0], v);
      sx[1] = std::max(sx[1], v);
    }
    for (double y : {lo.y, hi.y}) {
      const double v = e.y + (y - e.y) / w;
      sy[0] = std::min(sy[0], v);
      sy[1] = std::max(sy[1], v);
    }
  }
  int y0, y1;
  if (!pixel_range(sx[0], sx[1], cam.world_width, cam.width, cam.pad_x, out.x0, out.x1) ||
      !pixel_range(sy[0], sy[1], cam.world_height, cam.height, cam.pad_y, y0, y1))
    return false;
  out.r0 = cam.height - 1 - y1;  // world row y is image row H-1-y
  out.r1 = cam.height - 1 - y0;
  return true;
}

}  // namespace

ScreenBins build_screen_bins(const ScreenCamera& cam, std::span<const WidenedSphere> spheres,
                             int tile, double max_coverage) {
  ScreenBins bins;
  if (!(cam.eye.z != 0) || !(cam.world_width > 0) || !(cam.world_height > 0) || tile <= 0 ||
      cam.width < 1 || cam.height < 1 || cam.width > 65535 || cam.height > 65535)
    return bins;
  std::vector<Rect> rects(spheres.size());
  std::vector<bool> visible(spheres.size());
  const double budget = max_coverage * cam.width * static_cast<double>(cam.height);
  double covered = 0;
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    visible[i] = sphere_rect(cam, spheres[i], rects[i]);
    if (!visible[i]) continue;
    const Rect& r = rects[i];
    covered += (r.x1 - r.x0 + 1.0) * (r.r1 - r.r0 + 1.0);
    if (covered > budget) return bins;
  }

  bins.tile = tile;
  bins.tiles_x = (cam.width + tile - 1) / tile;
  bins.tiles_y = (cam.height + tile - 1) / tile;
  const std::size_t tiles = static_cast<std::size_t>(bins.tiles_x) * bins.tiles_y;
  auto for_tiles = [&](const Rect& r, auto&& fn) {
    for (int ty = r.r0 / tile; ty <= r.r1 / tile; ++ty)
      for (int tx = r.x0 / tile; tx <= r.x1 / tile; ++tx)
        fn(static_cast<std::size_t>(ty) * bins.tiles_x + tx);
  };
  bins.start.assign(tiles + 1, 0);
  for (std::size_t i = 0; i < spheres.size(); ++i)
    if (visible[i]) for_tiles(rects[i], [&](std::size_t t) { ++bins.start[t + 1]; });
  for (std::size_t t = 0; t < tiles; ++t) bins.start[t + 1] += bins.start[t];
  bins.entries.resize(bins.start[tiles]);
  std::vector<float> near(spheres.size());
  for (std::size_t i = 0; i < spheres.size(); ++i)
    near[i] = float_down(glm::length(spheres[i].centre - cam.eye) - spheres[i].radius);
  std::vector<std::uint32_t> fill(bins.start.begin(), bins.start.end() - 1);
  for (std::int32_t i : order_by_near(near)) {  // so that each tile lists nearest first
    if (!visible[i]) continue;
    const Rect& r = rects[i];
    const ScreenBinEntry e{i, near[i], static_cast<std::uint16_t>(r.x0),
                           static_cast<std::uint16_t>(r.x1), static_cast<std::uint16_t>(r.r0),
                           static_cast<std::uint16_t>(r.r1)};
    for_tiles(r, [&](std::size_t t) { bins.entries[fill[t]++] = e; });
  }
  return bins;
}

}  // namespace rayfarm
