// Surfaces of revolution of the course (revsurf): about an axis, radius r(y) of one of three
// profiles for 0 <= y <= height, open at both ends. The ray is met by finding the first t
// where |radial(t)|² − r(y(t))² changes sign, stepping by what a Lipschitz bound of that
// function allows (so no crossing is stepped over, but for chords shorter than a minimum
// step) and bisecting to the end of precision. Both profiles use it.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <span>

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

namespace revsurf_detail {

// Bisection of [a, b], where fl(f) has the sign of fa at a and the other at b, down to
// adjacent doubles: the b where it ends. Only the sign of fl(f(m)) at each midpoint steers it.
template <class F>
inline double bisect(const F& f, double a, double b, double fa, int steps = 200) {
  for (int k = 0; k < steps; ++k) {
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
  return b;
}

// The same bisection, two midpoints a round: f at the midpoint and at both midpoints it may
// lead to, evaluated side by side, so that one evaluation's latency serves two steps. The
// same midpoints decide, so the same answer; for an f of a few operations (the cone's), whose
// time is the chain from one midpoint to the next.
template <class F>
inline double bisect_by_twos(const F& f, double a, double b, double fa, int steps = 200) {
  const bool neg_a = fa <= 0;
  // x if `take`, else y: a select, not a branch (the signs are a coin toss).
  auto pick = [](bool take, double x, double y) {
    const std::uint64_t mask = std::uint64_t{0} - take;
    return std::bit_cast<double>((std::bit_cast<std::uint64_t>(x) & mask) |
                                 (std::bit_cast<std::uint64_t>(y) & ~mask));
  };
  for (int k = 0; k < steps;) {
    const double m = 0.5 * (a + b);
    if (m <= a || m >= b) break;
    const double left = 0.5 * (a + m), right = 0.5 * (m + b);
    const double fm = f(m), fl = f(left), fr = f(right);
    const bool up = neg_a == (fm <= 0);  // a moves to m, and the next midpoint is right
    a = pick(up, m, a);
    b = pick(up, b, m);
    const double next = pick(up, right, left), fnext = pick(up, fr, fl);
    if (++k == steps || next <= a || next >= b) break;
    const bool up2 = neg_a == (fnext <= 0);
    a = pick(up2, next, a);
    b = pick(up2, b, next);
    ++k;
  }
  return b;
}

// How far fl(f) can lie from f in real arithmetic, for the two certificates below.
//
// Let f* be f in real arithmetic (the libm sine replaced by the true one; the cone's 2/3 is
// the double c = fl(2/3) that f multiplies by). For x >= 0, with p1 = fl(x rdd), p3 =
// fl(x fl(2 r0d + p1)) and q = fl(rr + p3) as f computes them, and Y = |y0| + x |dy|,
// |fl(f(x)) − f*(x)| <= E(x) = u (2.5 |q| + 2.5 |p3| + 1.5 x p1 + K), u = 2^-53, where
// K = 16 + 4 Y for the waves and K = 10 (4 + Y)² for the cone. The quadratic errs by at most
// u (1.001 |q| + 2.001 |p3| + x² rdd) (each operation by u times its result, carried through
// the products by x), and y = fl(y0 + fl(x dy)) by Δy <= 2.01u Y. The waves: the last
// subtraction errs by u (|q| + 2.26); r² by 2.25u + 3.01 (2u + Δy/2), r's rounding u plus half
// of the sine's error, taken as 2u (one ulp is at most u, as |sin| <= 1). In all at most
// u (2.001 |q| + 2.001 |p3| + x² rdd + 10.52 + 3.04 Y). The cone, with R = 4 + Y >= |r|:
// fl(c y) errs by 2.01u Y, r = fl(4 − fl(c y)) by u (2.01 Y + R) <= 3.01u R, r² by 6.03u R²
// and its rounding u R², the last subtraction by u (|q| + 1.01 R²): in all at most
// u (2.001 |q| + 2.001 |p3| + x² rdd + 8.05 R²). E's constants exceed those by a fifth and
// more, which covers E's own rounding (a few u, relative) and the difference between the
// computed q, p3 and exact ones. Over [x, x + w], |q| and |p3| grow by at most |q'| w <=
// 2 (|r0d| + (x + w) rdd) w, and the other terms are largest at x + w: over() bounds E there.
//
// |f*''| <= M2 = 2 rdd + 2 dy²: r²'' = dy² (sin²/2 − r cos) for a wave (or its twin), at most
// 2 dy², and 2 c² dy² for the cone. So if f*(A) lies within rA of cA and f*(B) within rB of
// cB, then at t = A + λ (B − A), f*(t) lies within (1 − λ) rA + λ rB + M2 (t − A)(B − t)/2 of
// L(t) = (1 − λ) cA + λ cB: between two lines, the lower from cA − rA to cB − rB, the upper
// from cA + rA to cB + rB, widened by M2 (B − A)²/8. Where the lower line exceeds that
// widening plus E's bound over [A, B], fl(f(t)) > 0; where the upper one is below minus that,
// fl(f(t)) < 0 (the margin D also takes 2u (|cA| + rA + |cB| + rB) for the rounding of the
// lines' ends). `trust` < 1 shrinks D: for tests only, to show that a wrong bound changes
// answers.
struct RoundingBound {
  static constexpr double u = 0x1p-53, slack = 1 + 0x1p-40;
  const RevsurfRay& r;
  bool cone;
  double trust;
  double ay0 = std::abs(r.y0), ady = std::abs(r.dy), a2r0d = 2 * std::abs(r.r0d);
  double m2_8 = 0.125 * slack * 2 * (r.rdd + r.dy * r.dy + 0x1p-1000);

  double k_term(double y) const { return cone ? 10 * (4 + y) * (4 + y) : 16 + 4 * y; }
  // E(x).
  double at(double x) const {
    const double p1 = x * r.rdd, p3 = x * (2 * r.r0d + p1), q = r.rr + p3;
    return u * (2.5 * (std::abs(q) + std::abs(p3)) + 1.5 * x * p1 + k_term(ay0 + x * ady));
  }
  // E's bound over [x, x + w].
  double over(double x, double w) const {
    const double p1 = x * r.rdd, p3 = x * (2 * r.r0d + p1), q = r.rr + p3, xe = x + w;
    return u * (2.5 * (std::abs(q) + std::abs(p3)) + 5 * (a2r0d + 2 * xe * r.rdd) * w +
                1.5 * xe * (xe * r.rdd) + k_term(ay0 + xe * ady));
  }
  // D for [a, a + w] with the enclosures ca ± ra and cb ± rb at its ends.
  double margin(double a, double w, double ca, double ra, double cb, double rb) const {
    return trust * slack *
           (m2_8 * w * w + over(a, w) + 2 * u * (std::abs(ca) + ra + std::abs(cb) + rb));
  }
};

// Whether fl(f) certainly keeps the sign it has at t (f(t) = v) at every x in [t, hi]: then
// the stepping below meets no change of sign there and returns -1. Rays leaving a surface
// mostly go away from it, where that is shown in a few intervals, each as wide as the
// curvature term allows (three quarters of the margin |v| − E): a handful of evaluations
// instead of a step each |v|/L. False when it cannot show it (the search then runs as
// before). The width is a guess the checks below make safe whatever it is: a quarter took
// 2.56 evaluations a ray on kinds-mix, three quarters 2.11, with 9% more rays left to the
// search (3,702 of 267,671).
template <class F>
inline bool certainly_no_crossing(const F& f, const RoundingBound& bound, double t, double v,
                                  double hi) {
  const bool positive = v > 0;
  double x = t, cx = v, rx = bound.at(t);
  for (int i = 0; i < 12; ++i) {
    const double room = std::abs(cx) - rx;
    if (!(room > 0)) return false;
    const double step = std::sqrt(0.75 * room / bound.m2_8);
    const bool last = !(x + step < hi);
    const double z = last ? hi : x + step, w = z - x;
    const double cz = f(z), rz = bound.at(z);
    const double D = bound.margin(x, w, cx, rx, cz, rz);
    if (positive ? !(cx - rx > D && cz - rz > D) : !(cx + rx < -D && cz + rz < -D)) return false;
    if (last) return true;
    x = z, cx = cz, rx = rz;
  }
  return false;
}

// The same bisection for the two waves (r = 1 + cos(y)/2 or 1 + sin(y)/2), the same midpoints
// and the same answer, with a sine only where the sign of fl(f(m)) is not certain otherwise,
// by RoundingBound's lines. Near A they give a certain sign for t − A < d1, near B for B − t
// < d2 (the lines are straight, so each region is an interval from its end), and d1, d2 are
// computed short by 2^-40 relative, more than their rounding and that of t − A.
//
// The bisection takes every midpoint in those regions with its certain sign: a subtraction
// and a comparison. At a midpoint in neither, it derives the regions again from the bracket
// it has come to: an end reached by a certain sign gets the enclosure above (its center
// computed with an error below 8u (|cA| + |cB|), λ's within 4u (rA + rB)), or, where that
// is wider than 4 E, fl(f) ± E evaluated there (evaluations off the midpoints only cost
// time). A midpoint still uncertain is evaluated, or, once the regions leave most of the
// bracket uncertain (the rounding noise about the root, where the rest of the midpoints
// fall), the plain bisection takes over for the steps left. Anything not finite (overflow,
// NaN) leaves the regions empty, so f is evaluated, as before. `trust` < 1 shrinks the
// margin: for tests only, to show that a wrong certificate changes answers. revsurf.cpp's
// lanes (WaveBisection, and the stepping and the cone's bisection) repeat these searches
// operation for operation: a change here is a change there, which the exactness tests'
// batched rays check.
template <class F>
inline double bisect_wave(const F& f, const RoundingBound& bound, double a, double b, double fa,
                          double fb) {
  constexpr double u = RoundingBound::u, slack = RoundingBound::slack, shrink = 1 - 0x1p-40;
  const double m2_8 = bound.m2_8;
  auto error = [&](double x) { return bound.at(x); };
  const bool neg_a = fa <= 0;
  // Enclosures at a and b (valid unless that end was reached by a certain sign since the
  // regions were derived), the regions' bracket [A, B] with its enclosures, and the regions.
  double ca = fa, ra = error(a), cb = fb, rb = error(b);
  double A = a, B = b, cA = ca, rA = ra, cB = cb, rB = rb, Aeval = a, Beval = b, d1 = -1, d2 = -1;
  bool neg1 = false, neg2 = false;
  auto derive = [&] {
    A = a, B = b, cA = ca, rA = ra, cB = cb, rB = rb;
    const double w = b - a;
    const double D = bound.margin(a, w, ca, ra, cb, rb);
    const double lo_a = ca - ra, lo_b = cb - rb, up_a = ca + ra, up_b = cb + rb;
    d1 = d2 = -1;  // NaN anywhere leaves them so
    if (lo_a > D) {
      d1 = lo_b < lo_a ? shrink * ((lo_a - D) / (lo_a - lo_b) * w) : w;
      neg1 = false;
    } else if (up_a < -D) {
      d1 = up_b > up_a ? shrink * ((-D - up_a) / (up_b - up_a) * w) : w;
      neg1 = true;
    }
    if (lo_b > D) {
      d2 = lo_a < lo_b ? shrink * ((lo_b - D) / (lo_b - lo_a) * w) : w;
      neg2 = false;
    } else if (up_b < -D) {
      d2 = up_a > up_b ? shrink * ((-D - up_b) / (up_a - up_b) * w) : w;
      neg2 = true;
    }
  };
  // The enclosure of f* at t in [A, B] that the regions' lines give.
  auto enclose = [&](double t, double& c, double& rad) {
    const double lambda = (t - A) / (B - A);
    c = cA + (cB - cA) * lambda;
    rad = slack * ((1 - lambda) * rA + lambda * rB + 4 * u * (rA + rB) +
                   8 * u * (std::abs(cA) + std::abs(cB)) + 4 * m2_8 * (t - A) * (B - t));
  };
  derive();
  for (int k = 0; k < 200; ++k) {
    const double m = 0.5 * (a + b);
    if (m <= a || m >= b) break;
    bool neg_m;
    if (m - A < d1) {
      neg_m = neg1;
    } else if (B - m < d2) {
      neg_m = neg2;
    } else {
      if (a != A || b != B) {  // regions from the bracket come to
        // An end reached by a certain sign: the lines' enclosure there, or where that is
        // much wider than E, f evaluated.
        if (a != A && a != Aeval) {
          enclose(a, ca, ra);
          const double e = error(a);
          if (!(ra <= 4 * e)) ca = f(a), ra = e, Aeval = a;
        }
        if (b != B && b != Beval) {
          enclose(b, cb, rb);
          const double e = error(b);
          if (!(rb <= 4 * e)) cb = f(b), rb = e, Beval = b;
        }
        derive();
      }
      if (m - A < d1) {
        neg_m = neg1;
      } else if (B - m < d2) {
        neg_m = neg2;
      } else {
        // Most of the bracket uncertain: it is within the rounding noise about the root,
        // where the rest of the midpoints will be too. Plain bisection from here.
        if (!(d1 + d2 > 0.5 * (b - a))) return bisect(f, a, b, neg_a ? -1.0 : 1.0, 200 - k);
        const double fm = f(m);
        neg_m = fm <= 0;
        if (neg_a == neg_m) {
          a = m, ca = fm, ra = error(m), Aeval = m;
        } else {
          b = m, cb = fm, rb = error(m), Beval = m;
        }
        continue;
      }
    }
    if (neg_a == neg_m) {
      a = m;
    } else {
      b = m;
    }
  }
  return b;
}

// No limit: the crossing itself is wanted.
struct NoLimit {
  static bool reached(double) { return false; }
  static bool before(double, double) { return false; }
};

// The function whose change of sign first_crossing finds: |radial(t)|² − r(y(t))², as
// computed (its rounding is RoundingBound's subject).
[[gnu::always_inline]] inline double crossing_f(int surfer, const RevsurfRay& r, double t) {
  const double rad = revsurf_radius(surfer, r.y0 + t * r.dy);
  return r.rr + t * (2 * r.r0d + t * r.rdd) - rad * rad;
}

// Where first_crossing searches: the part of the ray inside the surface's cylinder and its
// height, with the stepping's Lipschitz bound and least step there; false when that part is
// empty (the answer is -1).
struct SearchSpan {
  double lo, hi, lipschitz, min_step;
};

[[gnu::always_inline]] inline bool search_span(int surfer, double height, const RevsurfRay& r,
                                               SearchSpan& span) {
  height = revsurf_top(surfer, height);
  double lo = 0, hi = 1e300;
  if (r.dy != 0) {
    double t1 = -r.y0 / r.dy, t2 = (height - r.y0) / r.dy;
    if (t1 > t2) std::swap(t1, t2);
    lo = std::max(lo, t1);
    hi = std::min(hi, t2);
  } else if (r.y0 < 0 || r.y0 > height) {
    return false;
  }
  const double rmax = revsurf_max_radius(surfer, height);
  if (r.rdd > 0) {
    const double disc = r.r0d * r.r0d - r.rdd * (r.rr - rmax * rmax);
    if (disc < 0) return false;
    const double s = std::sqrt(disc);
    lo = std::max(lo, (-r.r0d - s) / r.rdd);
    hi = std::min(hi, (-r.r0d + s) / r.rdd);
  } else if (r.rr > rmax * rmax) {
    return false;
  }
  if (!(lo < hi) || !std::isfinite(hi)) return false;
  // |f'| <= 2|r0d + t rdd| + 2 r |r'| |dy|, the first term largest at an end of [lo, hi].
  const double slope_bound = surfer == 1 ? 2 * rmax * 2.0 / 3 : 2 * 1.5 * 0.5;
  span.lipschitz = 2 * std::max(std::abs(r.r0d + lo * r.rdd), std::abs(r.r0d + hi * r.rdd)) +
                   slope_bound * std::abs(r.dy);
  span.min_step = (hi - lo) / 512;
  span.lo = lo;
  span.hi = hi;
  return true;
}

// revsurf_first_crossing below, with the certificates' `trust` (RoundingBound); `shown`
// (tests) learns whether certainly_no_crossing gave the answer. A shadow ray asks only
// whether the crossing comes before its light: with a `limit`, once the stepping has a
// bracket (t, next] that `limit.before(t, next)` says lies before it, next is returned
// instead of the bisected crossing, and once `limit.reached(t)` says no crossing beyond t
// counts, -1 (the stepping's points are the same ones; only the answer's use differs).
template <class Limit = NoLimit>
inline double first_crossing(int surfer, double height, const RevsurfRay& r, bool own, double trust,
                             bool* shown = nullptr, const Limit& limit = {}) {
  SearchSpan span;
  if (!search_span(surfer, height, r, span)) return -1;
  const double lo = span.lo, hi = span.hi, lipschitz = span.lipschitz, min_step = span.min_step;
  auto f = [&](double t) { return crossing_f(surfer, r, t); };
  // Off the surface a ray starts on (own), the side it is on decides: the search starts a
  // least step in, and f at lo is never needed.
  const double t0 = own ? std::min(hi, lo + min_step) : lo;
  double t = t0, v = f(t0);
  const RoundingBound bound{r, surfer == 1, trust};
  if (own) {
    if (certainly_no_crossing(f, bound, t, v, hi)) {
      if (shown) *shown = true;
      return -1;
    }
  }
  for (int i = 0; i < 4096 && t < hi; ++i) {
    if (limit.reached(t)) return -1;  // every crossing from here lies beyond t
    const double step = std::max(std::abs(v) / lipschitz, min_step);
    const double next = std::min(t + step, hi);
    const double w = f(next);
    if ((v <= 0) != (w <= 0)) {
      if (limit.before(t, next)) return next;  // the crossing is in (t, next]
      const double b =
          surfer == 1 ? bisect_by_twos(f, t, next, v) : bisect_wave(f, bound, t, next, v, w);
      if (b > 0) return b;
    }
    t = next;
    v = w;
  }
  return -1;
}

// The crossings of n rays side by side in vector lanes (geometry/revsurf.cpp), the same
// doubles as first_crossing's with own = false and no limit, but NaN where a bracket's
// bisection ended at b <= 0 (first_crossing then steps on: the caller asks it). Only where
// lanes_available().
void crossings_in_lanes(int surfer, double height, const RevsurfRay* rays, int n, double* out);
bool lanes_available();

}  // namespace revsurf_detail

// The first t > 0 at which the ray crosses the surface within 0 <= y <= height, or -1.
// `own`: the ray leaves the surface itself; the crossing it starts on does not count. With a
// `limit` (a shadow ray's question, in the caller's precision: see
// revsurf_detail::first_crossing), a value that question answers as it would the crossing.
template <class Limit = revsurf_detail::NoLimit>
inline double revsurf_first_crossing(int surfer, double height, const RevsurfRay& r, bool own,
                                     const Limit& limit = {}) {
  return revsurf_detail::first_crossing(surfer, height, r, own, 1.0, nullptr, limit);
}

// revsurf_first_crossing(surfer, height, rays[i], false) into out[i] for each i: the same
// doubles. Rays that do not start on the surface, many of them (a screen bin's): they are
// searched side by side in vector lanes where the processor has AVX2, each lane with its
// own ray's steps and bisection, so the latency of one ray's chain serves four.
void revsurf_first_crossings(int surfer, double height, std::span<const RevsurfRay> rays,
                             std::span<double> out);

}  // namespace rayfarm
