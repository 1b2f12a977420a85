// Surfaces of revolution of the course (revsurf): about an axis, radius r(y) of one of three
// profiles for 0 <= y <= height, open at both ends. The ray is met by finding the first t
// where |radial(t)|² − r(y(t))² changes sign, stepping by what a Lipschitz bound of that
// function allows (so no crossing is stepped over, but for chords shorter than a minimum
// step) and bisecting to the end of precision. Both profiles use it.
#pragma once

#include <algorithm>
#include <cmath>

namespace rayfarm {

// r(y) of profile `surfer` and its slope: 1 the cone 4 − 2y/3, 2 the wave 1 + cos(y)/2,
// 3 the wave 1 + sin(y)/2 (docs/profiles.md §10, measured from the reference images).
inline double revsurf_radius(int surfer, double y, double* slope = nullptr) {
  switch (surfer) {
    case 1:
      if (slope) *slope = -2.0 / 3;
      return 4 - 2.0 / 3 * y;
    case 2:
      if (slope) *slope = -0.5 * std::sin(y);
      return 1 + 0.5 * std::cos(y);
    default:
      if (slope) *slope = 0.5 * std::cos(y);
      return 1 + 0.5 * std::sin(y);
  }
}

// The cone's radius reaches 0 at y = 6: a radius cannot be negative, so the cone ends at
// its apex, whatever height is written.
inline double revsurf_top(int surfer, double height) {
  return surfer == 1 ? std::min(height, 6.0) : height;
}

// The largest r(y) for 0 <= y <= height.
inline double revsurf_max_radius(int surfer, double /*height*/) { return surfer == 1 ? 4.0 : 1.5; }

// A ray in the surface's frame: y0 + t·dy along the axis, r0 + t·rd across it, given by
// |r0|², r0·rd and |rd|².
struct RevsurfRay {
  double y0, dy, rr, r0d, rdd;
};

// The first t > 0 at which the ray crosses the surface within 0 <= y <= height, or -1.
// `own`: the ray leaves the surface itself; the crossing it starts on does not count.
inline double revsurf_first_crossing(int surfer, double height, const RevsurfRay& r, bool own) {
  height = revsurf_top(surfer, height);
  double lo = 0, hi = 1e300;
  if (r.dy != 0) {
    double t1 = -r.y0 / r.dy, t2 = (height - r.y0) / r.dy;
    if (t1 > t2) std::swap(t1, t2);
    lo = std::max(lo, t1);
    hi = std::min(hi, t2);
  } else if (r.y0 < 0 || r.y0 > height) {
    return -1;
  }
  const double rmax = revsurf_max_radius(surfer, height);
  if (r.rdd > 0) {
    const double disc = r.r0d * r.r0d - r.rdd * (r.rr - rmax * rmax);
    if (disc < 0) return -1;
    const double s = std::sqrt(disc);
    lo = std::max(lo, (-r.r0d - s) / r.rdd);
    hi = std::min(hi, (-r.r0d + s) / r.rdd);
  } else if (r.rr > rmax * rmax) {
    return -1;
  }
  if (!(lo < hi) || !std::isfinite(hi)) return -1;
  auto f = [&](double t) {
    const double rad = revsurf_radius(surfer, r.y0 + t * r.dy);
    return r.rr + t * (2 * r.r0d + t * r.rdd) - rad * rad;
  };
  // |f'| <= 2|r0d + t rdd| + 2 r |r'| |dy|, the first term largest at an end of [lo, hi].
  const double slope_bound = surfer == 1 ? 2 * rmax * 2.0 / 3 : 2 * 1.5 * 0.5;
  const double lipschitz = 2 * std::max(std::abs(r.r0d + lo * r.rdd), std::abs(r.r0d + hi * r.rdd)) +
                           slope_bound * std::abs(r.dy);
  const double min_step = (hi - lo) / 512;
  double t = lo, v = f(t);
  if (own) {  // off the surface it starts on: the side the ray is on decides
    t = std::min(hi, lo + min_step);
    v = f(t);
  }
  for (int i = 0; i < 4096 && t < hi; ++i) {
    const double step = std::max(std::abs(v) / lipschitz, min_step);
    const double next = std::min(t + step, hi);
    const double w = f(next);
    if ((v <= 0) != (w <= 0)) {
      double a = t, b = next, fa = v;
      for (int k = 0; k < 200; ++k) {
        const double m = 0.5 * (a + b);
        if (m <= a || m >= b) break;
        const double fm = f(m);
        if ((fa <= 0) == (fm <= 0)) {
          a = m;
          fa = fm;
        } else {
          b = m;
        }
      }
      if (b > 0) return b;
    }
    t = next;
    v = w;
  }
  return -1;
}

}  // namespace rayfarm
