// The cone's search for many rays at once (revsurf.h, revsurf_first_crossings). One ray's
// search is a chain: each step's size comes from f at the last point, each midpoint of the
// bisection from the sign of f at the one before, a few dependent operations each. Four rays
// in the four lanes of AVX2 vectors make four chains for the price of one; every lane does
// the operations first_crossing does, in its order, so each gets the same doubles (IEEE
// arithmetic is the same in a lane as in a scalar register, and nothing is contracted).
//
// The stepping keeps its lanes full: a lane whose ray has found its bracket or left its span
// takes the next ray. The bisection runs the brackets eight at a time, two vectors side by
// side, as their counts of midpoints differ little. A bracket whose bisection ends at b <= 0
// (first_crossing then steps on) is left to first_crossing.
#include <cmath>
#include <cstdint>
#include <limits>

#include "geometry/revsurf.h"

namespace rayfarm {

namespace revsurf_detail {

#if defined(__x86_64__) && defined(__GNUC__)

namespace {

using D4 = double __attribute__((vector_size(32)));
using M4 = std::int64_t __attribute__((vector_size(32)));

#define RAYFARM_LANES [[gnu::target("avx2"), gnu::always_inline]] inline

RAYFARM_LANES D4 splat(double x) { return D4{x, x, x, x}; }
RAYFARM_LANES int mask_bits(M4 m) {
  return static_cast<int>((m[0] & 1) | (m[1] & 2) | (m[2] & 4) | (m[3] & 8));
}
RAYFARM_LANES D4 abs4(D4 x) {
  constexpr std::int64_t magnitude = 0x7fffffffffffffff;
  return reinterpret_cast<D4>(reinterpret_cast<M4>(x) & M4{magnitude, magnitude, magnitude, magnitude});
}
constexpr M4 kLane[4] = {M4{-1, 0, 0, 0}, M4{0, -1, 0, 0}, M4{0, 0, -1, 0}, M4{0, 0, 0, -1}};

// Four rays' frames, and the cone's f (first_crossing's, with revsurf_radius of surfer 1).
struct Rays4 {
  D4 y0, dy, rr, r0d, rdd;

  RAYFARM_LANES D4 f(D4 t) const {
    const D4 rad = splat(4) - splat(2.0 / 3) * (y0 + t * dy);
    return rr + t * (splat(2) * r0d + t * rdd) - rad * rad;
  }
  RAYFARM_LANES void set(int k, const RevsurfRay& r) {
    const M4 lane = kLane[k];
    y0 = lane ? splat(r.y0) : y0;
    dy = lane ? splat(r.dy) : dy;
    rr = lane ? splat(r.rr) : rr;
    r0d = lane ? splat(r.r0d) : r0d;
    rdd = lane ? splat(r.rdd) : rdd;
  }
};

struct Bracket {
  int ray;
  double a, b, fa;
};

// Up to kChunk rays at a time, so the work lists live on the stack.
constexpr int kChunk = 128;

// The stepping of first_crossing's loop for the rays whose spans are `spans` (ray[q] is the
// ray of spans[q]): the brackets where f changes sign go to `brackets`, the rays that leave
// their span or run out of steps get -1.
struct Stepping {
  const RevsurfRay* rays;
  const int* ray;
  const SearchSpan* spans;
  int count;
  Rays4 r{};
  D4 t{}, hi{}, lipschitz{}, min_step{}, steps{};
  int lane_ray[4] = {-1, -1, -1, -1};
  int live = 0, next = 0;

  // Lane k takes the next ray, at the start of its span.
  RAYFARM_LANES void take(int k) {
    const SearchSpan& s = spans[next];
    r.set(k, rays[ray[next]]);
    const M4 lane = kLane[k];
    t = lane ? splat(s.lo) : t;
    hi = lane ? splat(s.hi) : hi;
    lipschitz = lane ? splat(s.lipschitz) : lipschitz;
    min_step = lane ? splat(s.min_step) : min_step;
    steps = lane ? splat(0) : steps;
    lane_ray[k] = ray[next++];
    live |= 1 << k;
  }

  RAYFARM_LANES int run(double* out, Bracket* brackets) {
    int found = 0;
    for (int k = 0; k < 4 && next < count; ++k) take(k);
    D4 v = r.f(t);
    while (live) {
      D4 step = abs4(v) / lipschitz;
      step = step < min_step ? min_step : step;  // std::max(step, min_step)
      D4 to = t + step;
      to = hi < to ? hi : to;  // std::min(t + step, hi)
      const D4 w = r.f(to);
      const M4 cross = (v <= 0) != (w <= 0);
      steps += splat(1);
      int ended = mask_bits(cross | ~(to < hi) | (steps >= splat(4096))) & live;
      const D4 from = t, f_from = v;
      t = to;
      v = w;
      if (!ended) continue;
      const int crossed = mask_bits(cross);
      M4 fresh{};
      while (ended) {
        const int k = __builtin_ctz(static_cast<unsigned>(ended));
        ended &= ended - 1;
        if (crossed >> k & 1)
          brackets[found++] = {lane_ray[k], from[k], to[k], f_from[k]};
        else
          out[lane_ray[k]] = -1;
        live &= ~(1 << k);
        if (next < count) {
          take(k);
          fresh |= kLane[k];
        }
      }
      if (mask_bits(fresh)) {
        const D4 f_fresh = r.f(t);
        v = fresh ? f_fresh : v;
      }
    }
    return found;
  }
};

[[gnu::target("avx2")]] int step_in_lanes(const RevsurfRay* rays, const int* ray,
                                          const SearchSpan* spans, int count, double* out,
                                          Bracket* brackets) {
  Stepping s{rays, ray, spans, count};
  return s.run(out, brackets);
}

// Four brackets' bisections (first_crossing's bisect_by_twos takes the same midpoints as
// the plain bisection, which this is).
struct Bisection4 {
  Rays4 r;
  D4 a, b;
  M4 neg_a, going;
  int first, count;

  RAYFARM_LANES void start(const RevsurfRay* rays, const Bracket* brackets, int total, int at) {
    first = at;
    count = std::max(0, std::min(4, total - at));
    D4 fa = splat(0);
    r = Rays4{};
    for (int k = 0; k < 4; ++k) {
      const Bracket& x = brackets[std::min(at + k, total - 1)];  // spare lanes repeat one
      r.set(k, rays[x.ray]);
      a[k] = x.a;
      b[k] = x.b;
      fa[k] = x.fa;
    }
    neg_a = fa <= 0;
    going = count > 0 ? M4{-1, -1, -1, -1} : M4{0, 0, 0, 0};
  }
  // One midpoint in each lane still going; false when none is.
  RAYFARM_LANES bool halve(D4& m) {
    m = splat(0.5) * (a + b);
    going &= (m > a) & (m < b);
    return mask_bits(going) != 0;
  }
  RAYFARM_LANES void take(D4 m, D4 fm) {
    const M4 up = going & (neg_a == (fm <= 0));
    a = up ? m : a;
    b = (going & ~up) ? m : b;
  }
  RAYFARM_LANES void finish(const Bracket* brackets, double* out) const {
    for (int k = 0; k < count; ++k)
      out[brackets[first + k].ray] = b[k] > 0 ? b[k] : std::numeric_limits<double>::quiet_NaN();
  }
};

[[gnu::target("avx2")]] void bisect_in_lanes(const RevsurfRay* rays, const Bracket* brackets,
                                             int total, double* out) {
  for (int at = 0; at < total; at += 8) {
    Bisection4 x, y;
    x.start(rays, brackets, total, at);
    y.start(rays, brackets, total, at + 4);
    for (int k = 0; k < 200; ++k) {
      D4 mx, my;
      const bool gx = x.halve(mx), gy = y.halve(my);
      if (!gx && !gy) break;
      const D4 fx = x.r.f(mx), fy = y.r.f(my);
      x.take(mx, fx);
      y.take(my, fy);
    }
    x.finish(brackets, out);
    y.finish(brackets, out);
  }
}

}  // namespace

bool lanes_available() {
  static const bool available = __builtin_cpu_supports("avx2");
  return available;
}

void cone_crossings_in_lanes(double height, const RevsurfRay* rays, int n, double* out) {
  for (int base = 0; base < n; base += kChunk) {
    const int count = std::min(kChunk, n - base);
    int ray[kChunk];
    SearchSpan spans[kChunk];
    Bracket brackets[kChunk];
    int searched = 0;
    for (int i = base; i < base + count; ++i) {
      if (search_span(1, height, rays[i], spans[searched]))
        ray[searched++] = i;
      else
        out[i] = -1;
    }
    const int found = step_in_lanes(rays, ray, spans, searched, out, brackets);
    bisect_in_lanes(rays, brackets, found, out);
  }
}

#else

bool lanes_available() { return false; }
void cone_crossings_in_lanes(double, const RevsurfRay*, int, double*) {}

#endif

}  // namespace revsurf_detail

void revsurf_first_crossings(int surfer, double height, std::span<const RevsurfRay> rays,
                             std::span<double> out) {
  const int n = static_cast<int>(rays.size());
  if (surfer == 1 && revsurf_detail::lanes_available()) {
    revsurf_detail::cone_crossings_in_lanes(height, rays.data(), n, out.data());
    for (int i = 0; i < n; ++i)  // the rare bracket the lanes left (NaN): first_crossing's
      if (std::isnan(out[i])) out[i] = revsurf_first_crossing(surfer, height, rays[i], false);
    return;
  }
  for (int i = 0; i < n; ++i) out[i] = revsurf_first_crossing(surfer, height, rays[i], false);
}

}  // namespace rayfarm
