// Screen bin construction: each widened sphere's outline, seen from the eye, is bounded on
// the screen plane by its tangents along each axis, turned into a padded pixel rectangle and
// entered in every tile it reaches.
#include "accel/screen_bins.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

namespace rayfarm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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

// Where on the screen (z = 0) the lines from the eye meet a sphere, along one screen axis:
// a column (or row) is reachable when the plane through the eye and it, parallel to the other
// axis, cuts the sphere; in the plane of this axis and z that is the disc (c, r) seen from
// the eye (e, ez), and the range lies between its two tangents. The disc must lie wholly in
// front of the eye. False when a tangent runs (nearly) parallel to the screen.
bool tangent_range(double e, double ez, double c, double cz, double r, double& lo, double& hi) {
  const double va = c - e, vz = cz - ez;
  const double d2 = va * va + vz * vz;
  r += 1e-9 * std::sqrt(d2);  // the rounding below, many times over
  const double h2 = d2 - r * r;
  if (!(h2 > 0)) return false;
  const double h = std::sqrt(h2);
  double at[2];
  for (int k = 0; k < 2; ++k) {
    const double sign = k ? 1.0 : -1.0;
    // The tangent direction: v turned by the angle whose sine is r / |v|.
    const double ua = h * va - sign * r * vz, uz = h * vz + sign * r * va;
    if (!(uz * -ez > 0)) return false;  // towards the screen, or no bound
    at[k] = e - ez * ua / uz;
  }
  lo = std::min(at[0], at[1]);
  hi = std::max(at[0], at[1]);
  return std::isfinite(lo) && std::isfinite(hi);
}

// The rectangle of pixels whose primary rays can meet the sphere; false if no ray can.
bool sphere_rect(const ScreenCamera& cam, const WidenedSphere& s, Rect& out) {
  const glm::dvec3& e = cam.eye;
  // Along a primary ray, w = (ez - z) / ez runs from 0 at the eye to 1 on the screen.
  const double w_lo = (e.z - (s.centre.z - s.radius)) / e.z;
  const double w_hi = (e.z - (s.centre.z + s.radius)) / e.z;
  const double w_min = std::min(w_lo, w_hi), w_max = std::max(w_lo, w_hi);
  if (!(w_max > 0)) return false;  // wholly behind the eye
  const Rect all{0, cam.width - 1, 0, cam.height - 1};
  out = all;
  int y0 = 0, y1 = cam.height - 1;
  if (!(w_min > 0)) {
    // Around the eye's plane. A ray meets its points X with 0 < w <= w_max on the screen at
    // e + (X - e) / w: where all of the sphere lies to one side of the eye along an axis, at
    // least its nearest distance / w_max to that side (and up to infinity).
    auto side = [&](double e_a, double c_a, double world, int count, double pad, int& lo,
                    int& hi) {
      const double below = e_a - (c_a + s.radius), above = (c_a - s.radius) - e_a;
      if (above > 0) return pixel_range(e_a + above / w_max, kInf, world, count, pad, lo, hi);
      if (below > 0) return pixel_range(-kInf, e_a - below / w_max, world, count, pad, lo, hi);
      return true;
    };
    if (!side(e.x, s.centre.x, cam.world_width, cam.width, cam.pad_x, out.x0, out.x1) ||
        !side(e.y, s.centre.y, cam.world_height, cam.height, cam.pad_y, y0, y1))
      return false;
    out.r0 = cam.height - 1 - y1;
    out.r1 = cam.height - 1 - y0;
    return true;
  }
  double x_lo, x_hi, y_lo, y_hi;
  if (tangent_range(e.x, e.z, s.centre.x, s.centre.z, s.radius, x_lo, x_hi) &&
      !pixel_range(x_lo, x_hi, cam.world_width, cam.width, cam.pad_x, out.x0, out.x1))
    return false;
  if (tangent_range(e.y, e.z, s.centre.y, s.centre.z, s.radius, y_lo, y_hi) &&
      !pixel_range(y_lo, y_hi, cam.world_height, cam.height, cam.pad_y, y0, y1))
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
  // Nearest first, so that each tile lists nearest first. That order is no order in memory:
  // each sphere's rectangle and near bound are asked for some places ahead (as the light
  // buffers' build does).
  const std::vector<std::int32_t> order = order_by_near(near);
  constexpr std::size_t kAhead = 16;
  for (std::size_t k = 0; k < order.size(); ++k) {
    if (k + kAhead < order.size()) {
      __builtin_prefetch(&rects[order[k + kAhead]]);
      __builtin_prefetch(&near[order[k + kAhead]]);
    }
    const std::int32_t i = order[k];
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
