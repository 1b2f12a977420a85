// The attribute groups the plane-like kinds share: the plane (normal, point) and its window
// (xdir, dimensions).
#pragma once

#include <optional>

#include <glm/geometric.hpp>

#include "geometry/frame.h"
#include "scene/registry.h"

namespace rayfarm::entities {

inline std::optional<Plane> read_plane(EntityReader& r) {
  auto n = r.vec3("normal"), p = r.vec3("point");
  if (!n || !p) return std::nullopt;
  return Plane{*n, *p};
}

// xdir and a size under `size_key`; xdir must have a part in the plane, which is its x axis.
// Read whether or not the plane could be (nothing without it): the window's own errors are
// reported with the plane's, not one fix later.
inline std::optional<Window> read_window(EntityReader& r, const std::optional<Plane>& plane,
                                         std::string_view size_key = "dimensions") {
  auto xdir = r.vec3("xdir");
  auto dims = r.pair(size_key);
  if (!xdir || !plane) return std::nullopt;
  if (!plane_frame(plane->normal, *xdir)) {
    r.error("out-of-range",
            "'xdir' must not be parallel to 'normal': its part in the plane is the x axis of " +
                r.describe(),
            r.find("xdir")->where);
    return std::nullopt;
  }
  if (!dims) return std::nullopt;
  return Window{*xdir, (*dims)[0], (*dims)[1]};
}

}  // namespace rayfarm::entities
