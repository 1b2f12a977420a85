// Mirror bins: screen bins for the reflection rays that primary rays send off a plane. Such
// a ray leaves the hit point p along the primary ray's direction mirrored in the plane, so
// mirrored back it is the rest of the primary ray beyond p: it meets a sphere exactly when
// the primary ray, continued through the plane, meets the sphere's mirror image. Bins built
// over the mirrored spheres, from the same eye through the same pixels, therefore list each
// pixel's candidates for its reflection ray; the tracer still runs its own sphere test on
// the real ray.
//
// The real reflection ray is not exactly the mirrored primary ray: its origin is the rounded
// hit point (a few epsilons of |eye|, |p| and the plane's point off the plane) and its
// direction the rounded reflection of the rounded direction. Over a length of at most
// |p| + the scene's extent that moves it by tens of epsilons of those coordinates; the
// caller widens the spheres by that and by the rounding of the sphere test, for origins
// within a reach it then checks per ray.
#pragma once

#include <span>

#include "accel/screen_bins.h"

namespace rayfarm {

// Bins over the spheres mirrored in the plane through `point` with normal `normal`; empty
// as build_screen_bins declines, or when the eye lies in the plane.
ScreenBins build_mirror_bins(const ScreenCamera& camera, std::span<const WidenedSphere> spheres,
                             const glm::dvec3& normal, const glm::dvec3& point, int tile,
                             double max_coverage);

// A lower bound on the t at which a reflection ray (from a primary hit at distance t_primary
// along the primary ray) can meet a sphere whose mirror image is no nearer the eye than
// `near`: the eye, p and the mirror image form a triangle. `slack` covers the rounding of
// t_primary and of the sphere test's t (whose near root can fall short of the true distance
// by about sqrt(epsilon) of it when the ray grazes).
inline double mirror_near(double near, double t_primary, double slack) {
  return near - t_primary - slack * (near + t_primary);
}

}  // namespace rayfarm
