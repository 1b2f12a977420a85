// Surfaces of revolution as the reference program drew them (COURSE §10): about the axis
// through `base` along `axis`, axial coordinate y in [0, height], radius r(y) of the
// course's profile k. Its root finder is unknown; this one finds the first crossing of
// |radial|² − r(y)² along the ray by stepping and bisection, in extended precision.
#pragma once

#include <cmath>

#include "render/cpsc102/reference_scene.h"

namespace rayfarm::cpsc102 {

// r(y) and r'(y) of profile k: 1 a cone 4 − (2/3)y, 2 the wave 1 + cos(y)/2, 3 1 + sin(y)/2.
inline X revsurf_radius(int k, X y, X* slope = nullptr) {
  switch (k) {
    case 1:
      if (slope) *slope = -2.0L / 3;
      return 4 - 2.0L / 3 * y;
    case 2:
      if (slope) *slope = -0.5L * std::sin(y);
      return 1 + 0.5L * std::cos(y);
    default:
      if (slope) *slope = 0.5L * std::cos(y);
      return 1 + 0.5L * std::sin(y);
  }
}

// The first t > 0 where the ray meets the surface with 0 <= y <= height.
inline bool revsurf_hit(const RefObject& o, const V3& base, const V3& dir, double& t_hit) {
  const X q[3] = {static_cast<X>(base.x) - o.base.x, static_cast<X>(base.y) - o.base.y,
                  static_cast<X>(base.z) - o.base.z};
  const X a[3] = {o.axis.x, o.axis.y, o.axis.z};
  const X d[3] = {dir.x, dir.y, dir.z};
  const X y0 = q[0] * a[0] + q[1] * a[1] + q[2] * a[2];
  const X dy = d[0] * a[0] + d[1] * a[1] + d[2] * a[2];
  X r0[3], rd[3];
  for (int i = 0; i < 3; ++i) {
    r0[i] = q[i] - y0 * a[i];
    rd[i] = d[i] - dy * a[i];
  }
  const X rr = r0[0] * r0[0] + r0[1] * r0[1] + r0[2] * r0[2];
  const X rdd = rd[0] * rd[0] + rd[1] * rd[1] + rd[2] * rd[2];
  const X r0d = r0[0] * rd[0] + r0[1] * rd[1] + r0[2] * rd[2];
  const X h = o.rev_height;
  auto f = [&](X t) {
    const X y = y0 + t * dy;
    const X r = revsurf_radius(o.surfer, y);
    return rr + 2 * t * r0d + t * t * rdd - r * r;
  };
  auto in_range = [&](X t) {
    const X y = y0 + t * dy;
    return y >= 0 && y <= h;
  };
  // The span of t within the slab 0 <= y <= height.
  X lo = 0, hi = 1e30L;
  if (dy != 0) {
    X t1 = (0 - y0) / dy, t2 = (h - y0) / dy;
    if (t1 > t2) std::swap(t1, t2);
    lo = std::max<X>(lo, t1);
    hi = std::min<X>(hi, t2);
  } else if (y0 < 0 || y0 > h) {
    return false;
  }
  // ... and within the cylinder of the largest radius.
  const X rmax = o.surfer == 1 ? 4 : 1.5L;
  if (rdd > 0) {
    const X disc = r0d * r0d - rdd * (rr - rmax * rmax);
    if (disc < 0) return false;
    const X s = std::sqrt(disc);
    lo = std::max<X>(lo, (-r0d - s) / rdd);
    hi = std::min<X>(hi, (-r0d + s) / rdd);
  } else if (rr > rmax * rmax) {
    return false;
  }
  if (!(lo < hi)) return false;
  if (o.surfer == 1) {
    // The cone: f is quadratic in t.
    const X c1 = -2.0L / 3 * dy, c0 = 4 - 2.0L / 3 * y0;
    const X A = rdd - c1 * c1, B = 2 * (r0d - c0 * c1), C = rr - c0 * c0;
    X roots[2];
    int n = 0;
    if (A == 0) {
      if (B != 0) roots[n++] = -C / B;
    } else {
      const X disc = B * B - 4 * A * C;
      if (disc >= 0) {
        const X s = std::sqrt(disc);
        roots[n++] = (-B - s) / (2 * A);
        roots[n++] = (-B + s) / (2 * A);
        if (roots[0] > roots[1]) std::swap(roots[0], roots[1]);
      }
    }
    for (int i = 0; i < n; ++i)
      if (roots[i] > 0 && in_range(roots[i]) && revsurf_radius(1, y0 + roots[i] * dy) >= 0) {
        t_hit = static_cast<double>(roots[i]);
        return t_hit > 0;
      }
    return false;
  }
  // The waves: step along the span (finer than the profile's curvature and the ray's
  // grazing allow) for the first sign change, then bisect to the end of precision.
  const X span = hi - lo;
  const int steps = 512;
  X prev_t = std::max<X>(lo, 0), prev = f(prev_t);
  for (int i = 1; i <= steps; ++i) {
    const X t = lo + span * i / steps;
    if (t <= 0) continue;
    const X v = f(t);
    if ((prev <= 0) != (v <= 0)) {
      X a0 = prev_t, b0 = t, fa = prev;
      for (int it = 0; it < 80; ++it) {
        const X mid = (a0 + b0) / 2;
        const X fm = f(mid);
        if ((fa <= 0) == (fm <= 0)) {
          a0 = mid;
          fa = fm;
        } else {
          b0 = mid;
        }
      }
      const X root = (a0 + b0) / 2;
      if (root > 0 && in_range(root)) {
        t_hit = static_cast<double>(root);
        return t_hit > 0;
      }
    }
    prev_t = t;
    prev = v;
  }
  return false;
}

// The gradient of |radial|² − r(y)², normalised; the cone's axial part doubled (COURSE §10).
inline V3 revsurf_normal(const RefObject& o, const V3& p) {
  const V3 q = sub(p, o.base);
  const double y = dot(q, o.axis);
  const V3 radial = sub(q, scale(o.axis, y));
  X slope = 0;
  const X r = revsurf_radius(o.surfer, y, &slope);
  const X axial = -(o.surfer == 1 ? 2 : 1) * r * slope;
  return unit(add(radial, scale(o.axis, R(axial))));
}

}  // namespace rayfarm::cpsc102
