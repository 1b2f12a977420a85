// Surfaces of revolution as the reference program drew them (docs/profiles.md §10): about the axis
// through `base` along `axis`, axial coordinate y in [0, height], radius r(y) of the
// course's profile k. Its root finder is unknown (it misses some grazing hits that exist);
// this one is geometry/revsurf.h's.
#pragma once

#include <cmath>

#include "geometry/revsurf.h"
#include "render/cpsc102/reference_scene.h"

namespace rayfarm::cpsc102 {

// The first t > 0 where the ray meets the surface (geometry/revsurf.h), from the ray
// turned into the surface's frame in the program's arithmetic.
inline bool revsurf_hit(const RefObject& o, const V3& base, const V3& dir, double& t_hit) {
  const V3 q = sub(base, o.base);
  const double y0 = dot(q, o.axis), dy = dot(dir, o.axis);
  const V3 r0 = sub(q, scale(o.axis, y0)), rd = sub(dir, scale(o.axis, dy));
  const RevsurfRay ray{y0, dy, dot(r0, r0), dot(r0, rd), dot(rd, rd)};
  t_hit = revsurf_first_crossing(o.surfer, o.rev_height, ray, false);
  return t_hit > 0;
}

// The gradient of |radial|² − r(y)², normalised; the cone's axial part doubled (docs/profiles.md §10).
inline V3 revsurf_normal(const RefObject& o, const V3& p) {
  const V3 q = sub(p, o.base);
  const double y = dot(q, o.axis);
  const V3 radial = sub(q, scale(o.axis, y));
  double slope = 0;
  const double r = revsurf_radius(o.surfer, y, &slope);
  const X axial = -(o.surfer == 1 ? 2 : 1) * static_cast<X>(r) * slope;
  return unit(add(radial, scale(o.axis, R(axial))));
}

}  // namespace rayfarm::cpsc102
