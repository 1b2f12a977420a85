// Screen bins: primary visibility of spheres by projection instead of traversal. Every primary
// ray leaves the eye, so the pixels whose rays can meet a sphere form a small rectangle on the
// screen; each render tile lists the spheres whose rectangles reach it, nearest the eye first,
// and finds each pixel's closest sphere by testing only those (a z-buffer whose depth test is
// the tracer's own sphere test, so the answer is the loop's to the bit).
//
// A rectangle must never leave out a pixel the tracer's sphere test would hit: it comes from
// the sphere widened by the rounding margin of that test, padded by the jitter of sampling
// and the rounding of the primary ray's direction (in pixels, given by the caller).
#pragma once

#include <cstdint>
#include <glm/vec3.hpp>
#include <span>
#include <vector>

#include "accel/widened_sphere.h"

namespace rayfarm {

struct ScreenBinEntry {
  std::int32_t sphere;           // index into the scene's spheres
  float near;                    // no point of the widened sphere is nearer the eye than this
  std::uint16_t x0, x1, r0, r1;  // the pixel rectangle (columns; rows from the top), inclusive
};

struct ScreenBins {
  int tile = 0;  // tile side in pixels; 0: no bins (primary rays use the hierarchy)
  int tiles_x = 0;
  int tiles_y = 0;
  std::vector<std::uint32_t> start;  // a tile's entries: [start[t], start[t + 1])
  std::vector<ScreenBinEntry> entries;

  bool empty() const { return tile == 0; }
  std::span<const ScreenBinEntry> of_tile(int t) const {
    return {entries.data() + start[t], entries.data() + start[t + 1]};
  }
};

// The camera as the renderer maps pixels: pixel (x, y) looks from `eye` through
// (x / (width - 1) * world_width, y / (height - 1) * world_height, 0), y = 0 the bottom row.
struct ScreenCamera {
  glm::dvec3 eye;
  double world_width, world_height;
  int width, height;
  double pad_x, pad_y;  // pixels added on each side of every rectangle
};

// Bins the spheres for tiles of `tile` pixels; empty when the camera does not allow it (eye
// in the screen plane) or when the rectangles would cover more than `max_coverage` times the
// image (then tracing the hierarchy is cheaper).
ScreenBins build_screen_bins(const ScreenCamera& camera, std::span<const WidenedSphere> spheres,
                             int tile, double max_coverage);

}  // namespace rayfarm
