// The light buffer of Haines and Greenberg ("The Light Buffer: A Shadow-Testing Accelerator",
// IEEE CG&A 1986): a cube of directions around a point light, each cell listing the spheres
// that a line from the light through the cell can meet, nearest the light first. A shadow
// ray from p is a segment from p to the light, so it can only be blocked by spheres of the
// cell that (p - light) points into, and of those only by the ones that begin nearer the
// light than p. The spheres are the blockers' bounds: the scene's spheres, and the spheres
// about other shapes (the caller numbers them).
//
// It must never leave out a blocker the tracer's own test would report, or a shadow would
// change. The caller widens each sphere by a margin covering the rounding of that test and
// of the shadow ray's direction for points within `reach`; cells are found from the widened
// sphere's box, and the lookup declines (returns false) for points farther out.
#pragma once

#include <array>
#include <cstdint>
#include <glm/vec3.hpp>
#include <span>
#include <vector>

#include "accel/widened_sphere.h"

namespace rayfarm {

struct LightBufferEntry {
  std::int32_t blocker;  // index into the spheres the buffer was built from (or as renumbered)
  float near;           // no point of the widened sphere is nearer the light than this
};

struct LightBuffer {
  glm::dvec3 light{0};
  int n = 0;          // cells along each side of a cube face; 0: no buffer for this light
  double reach = 0;  // lookups need every |coordinate| of p within this
  std::array<std::int32_t, 6> face_base{};  // first cell of each face in `start`; -1: empty face
  std::vector<std::uint32_t> start;         // a cell's entries: [start[c], start[c + 1])
  std::vector<LightBufferEntry> entries;    // per cell, nearest first
  std::vector<std::int32_t> around;         // blockers whose spheres contain (or touch) the light

  bool empty() const { return n == 0; }

  struct Cell {
    const LightBufferEntry* begin = nullptr;
    const LightBufferEntry* end = nullptr;
    double limit_sq = 0;  // entries whose `near` squared exceeds this cannot block
  };
  // The cell a shadow ray from p belongs to, or false where the buffer cannot answer (p at
  // the light, p beyond `reach`, a non-finite p): the caller then tests another way. The
  // `around` spheres must be tested as well.
  bool lookup(const glm::dvec3& p, Cell& cell) const;
};

struct LightBufferLimits {
  int max_cells_per_side = 512;
  double max_entries_per_sphere = 48;  // on average; beyond, the cells are made coarser
  std::size_t max_around = 16;         // more spheres around the light: no buffer
};

// Builds the buffer of one light; empty (n = 0) when it would not pay.
LightBuffer build_light_buffer(const glm::dvec3& light, std::span<const WidenedSphere> spheres,
                               double reach, const LightBufferLimits& limits = {});

}  // namespace rayfarm
