// The search for many rays at once (revsurf.h, revsurf_first_crossings). One ray's search is
// a chain: each step's size comes from f at the last point, each midpoint of the bisection
// from the sign of f at the one before, a few dependent operations each. Four rays in the
// four lanes of AVX2 vectors make four chains for the price of one; every lane does the
// operations first_crossing does, in its order, so each gets the same doubles (IEEE
// arithmetic is the same in a lane as in a scalar register, and nothing is contracted).
//
// The stepping keeps its lanes full: a lane whose ray has found its bracket or left its span
// takes the next ray. The cone's f is a few operations, done in the lanes; the waves' f
// needs libm's sine, called lane by lane (the four calls are independent, so they overlap).
// The cone's bisection runs eight brackets at a time, two vectors side by side; the waves'
// is bisect_wave's, four at a time: the same regions, enclosures and evaluations in each
// lane as bisect_wave takes for its bracket, with f evaluated only in the lanes that need it.
// A bracket whose bisection ends at b <= 0 (first_crossing then steps on) is left to
// first_crossing.
#include "geometry/revsurf.h"

#include <cmath>
#include <cstdint>
#include <limits>

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
RAYFARM_LANES bool any(M4 m) { return mask_bits(m) != 0; }
RAYFARM_LANES D4 abs4(D4 x) {
  constexpr std::int64_t magnitude = 0x7fffffffffffffff;
  return reinterpret_cast<D4>(reinterpret_cast<M4>(x) &
                              M4{magnitude, magnitude, magnitude, magnitude});
}
// !(x <= a || x >= b), NaN included, as first_crossing's loops test it.
RAYFARM_LANES M4 strictly_inside(D4 x, D4 a, D4 b) { return ~((x <= a) | (x >= b)); }
constexpr M4 kLane[4] = {M4{-1, 0, 0, 0}, M4{0, -1, 0, 0}, M4{0, 0, -1, 0}, M4{0, 0, 0, -1}};

// Four rays' frames and their f: the cone's in the lanes (crossing_f with revsurf_radius of
// surfer 1, operation for operation), a wave's by crossing_f itself, lane by lane.
struct Rays4 {
  int surfer;
  const RevsurfRay* ray[4];
  D4 y0, dy, rr, r0d, rdd;

  RAYFARM_LANES D4 f(D4 t, int lanes = 15) const {
    if (surfer == 1) {
      const D4 rad = splat(4) - splat(2.0 / 3) * (y0 + t * dy);
      return rr + t * (splat(2) * r0d + t * rdd) - rad * rad;
    }
    D4 v = splat(0);
    for (int k = 0; k < 4; ++k)
      if (lanes >> k & 1) v[k] = crossing_f(surfer, *ray[k], t[k]);
    return v;
  }
  RAYFARM_LANES void set(int k, const RevsurfRay& r) {
    const M4 lane = kLane[k];
    ray[k] = &r;
    y0 = lane ? splat(r.y0) : y0;
    dy = lane ? splat(r.dy) : dy;
    rr = lane ? splat(r.rr) : rr;
    r0d = lane ? splat(r.r0d) : r0d;
    rdd = lane ? splat(r.rdd) : rdd;
  }
};

struct Bracket {
  int ray;
  double a, b, fa, fb;
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
  Rays4 r;
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
    D4 v = r.f(t, live);
    while (live) {
      D4 step = abs4(v) / lipschitz;
      step = step < min_step ? min_step : step;  // std::max(step, min_step)
      D4 to = t + step;
      to = hi < to ? hi : to;  // std::min(t + step, hi)
      const D4 w = r.f(to, live);
      const M4 cross = (v <= 0) != (w <= 0);
      steps += splat(1);
      int ended = mask_bits(cross | ~(to < hi) | (steps >= splat(4096))) & live;
      const D4 from = t, f_from = v;
      t = to;
      v = w;
      if (!ended) continue;
      const int crossed = mask_bits(cross);
      int fresh = 0;
      while (ended) {
        const int k = __builtin_ctz(static_cast<unsigned>(ended));
        ended &= ended - 1;
        if (crossed >> k & 1)
          brackets[found++] = {lane_ray[k], from[k], to[k], f_from[k], w[k]};
        else
          out[lane_ray[k]] = -1;
        live &= ~(1 << k);
        if (next < count) {
          take(k);
          fresh |= 1 << k;
        }
      }
      if (fresh) {
        const D4 f_fresh = r.f(t, fresh);
        for (int k = 0; k < 4; ++k)
          if (fresh >> k & 1) v = kLane[k] ? f_fresh : v;
      }
    }
    return found;
  }
};

[[gnu::target("avx2")]] int step_in_lanes(int surfer, const RevsurfRay* rays, const int* ray,
                                          const SearchSpan* spans, int count, double* out,
                                          Bracket* brackets) {
  Stepping s{rays, ray, spans, count, Rays4{surfer, {}, {}, {}, {}, {}, {}}};
  return s.run(out, brackets);
}

// Four brackets at once, spare lanes repeating one (their answers are not kept).
struct Lanes4 {
  Rays4 r;
  D4 a, b, fa, fb;
  int first, count;

  RAYFARM_LANES void start(int surfer, const RevsurfRay* rays, const Bracket* brackets, int total,
                           int at) {
    first = at;
    count = std::max(0, std::min(4, total - at));
    r = Rays4{surfer, {}, {}, {}, {}, {}, {}};
    a = b = fa = fb = splat(0);
    for (int k = 0; k < 4; ++k) {
      const Bracket& x = brackets[std::min(at + k, total - 1)];
      r.set(k, rays[x.ray]);
      a[k] = x.a;
      b[k] = x.b;
      fa[k] = x.fa;
      fb[k] = x.fb;
    }
  }
  RAYFARM_LANES M4 used() const {
    return count >= 4 ? M4{-1, -1, -1, -1} : M4{0 < count, 1 < count, 2 < count, 3 < count} * -1;
  }
  RAYFARM_LANES void finish(const Bracket* brackets, double* out) const {
    for (int k = 0; k < count; ++k)
      out[brackets[first + k].ray] = b[k] > 0 ? b[k] : std::numeric_limits<double>::quiet_NaN();
  }
};

// The cone's bisection: bisect_by_twos takes the same midpoints as the plain bisection,
// which this is.
struct ConeBisection : Lanes4 {
  M4 neg_a, going;

  RAYFARM_LANES void begin(const RevsurfRay* rays, const Bracket* brackets, int total, int at) {
    start(1, rays, brackets, total, at);
    neg_a = fa <= 0;
    going = used();
  }
  // One midpoint in each lane still going; false when none is.
  RAYFARM_LANES bool halve(D4& m) {
    m = splat(0.5) * (a + b);
    going &= strictly_inside(m, a, b);
    return any(going);
  }
  RAYFARM_LANES void take(D4 m, D4 fm) {
    const M4 up = going & (neg_a == (fm <= 0));
    a = up ? m : a;
    b = (going & ~up) ? m : b;
  }
};

[[gnu::target("avx2")]] void bisect_cones(const RevsurfRay* rays, const Bracket* brackets,
                                          int total, double* out) {
  for (int at = 0; at < total; at += 8) {
    ConeBisection x, y;
    x.begin(rays, brackets, total, at);
    y.begin(rays, brackets, total, at + 4);
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

// bisect_wave in four lanes. Each lane takes the branch bisect_wave takes for its bracket;
// the names are bisect_wave's, the arithmetic RoundingBound's, in their order.
struct WaveBisection : Lanes4 {
  static constexpr double u = RoundingBound::u, slack = RoundingBound::slack, shrink = 1 - 0x1p-40;
  D4 ay0, ady, a2r0d, m2_8;  // RoundingBound's, per lane (trust 1)
  D4 ca, ra, cb, rb, A, B, cA, rA, cB, rB, Aeval, Beval, d1, d2;
  M4 neg_a, neg1, neg2, plain, going;

  RAYFARM_LANES D4 k_term(D4 y) const { return splat(16) + splat(4) * y; }
  RAYFARM_LANES D4 error(D4 x) const {  // RoundingBound::at
    const D4 p1 = x * r.rdd, p3 = x * (splat(2) * r.r0d + p1), q = r.rr + p3;
    return splat(u) *
           (splat(2.5) * (abs4(q) + abs4(p3)) + splat(1.5) * x * p1 + k_term(ay0 + x * ady));
  }
  RAYFARM_LANES D4 over(D4 x, D4 w) const {  // RoundingBound::over
    const D4 p1 = x * r.rdd, p3 = x * (splat(2) * r.r0d + p1), q = r.rr + p3, xe = x + w;
    return splat(u) *
           (splat(2.5) * (abs4(q) + abs4(p3)) + splat(5) * (a2r0d + splat(2) * xe * r.rdd) * w +
            splat(1.5) * xe * (xe * r.rdd) + k_term(ay0 + xe * ady));
  }
  RAYFARM_LANES D4 margin(D4 x, D4 w, D4 cx, D4 rx, D4 cz, D4 rz) const {  // trust 1
    return splat(1.0 * slack) *
           (m2_8 * w * w + over(x, w) + splat(2 * u) * (abs4(cx) + rx + abs4(cz) + rz));
  }

  RAYFARM_LANES void begin(int surfer, const RevsurfRay* rays, const Bracket* brackets, int total,
                           int at) {
    start(surfer, rays, brackets, total, at);
    ay0 = ady = a2r0d = m2_8 = splat(0);
    for (int k = 0; k < 4; ++k) {
      const RoundingBound bound{*r.ray[k], false, 1.0};
      ay0[k] = bound.ay0;
      ady[k] = bound.ady;
      a2r0d[k] = bound.a2r0d;
      m2_8[k] = bound.m2_8;
    }
    neg_a = fa <= 0;
    ca = fa, ra = error(a), cb = fb, rb = error(b);
    A = a, B = b, cA = ca, rA = ra, cB = cb, rB = rb, Aeval = a, Beval = b;
    d1 = d2 = splat(-1);
    neg1 = neg2 = plain = M4{0, 0, 0, 0};
    derive(M4{-1, -1, -1, -1});
    going = used();
  }

  // bisect_wave's derive, in the lanes of `sel`.
  RAYFARM_LANES void derive(M4 sel) {
    A = sel ? a : A, B = sel ? b : B, cA = sel ? ca : cA, rA = sel ? ra : rA;
    cB = sel ? cb : cB, rB = sel ? rb : rB;
    const D4 w = b - a;
    const D4 D = margin(a, w, ca, ra, cb, rb);
    const D4 lo_a = ca - ra, lo_b = cb - rb, up_a = ca + ra, up_b = cb + rb;
    const M4 pos1 = lo_a > D, low1 = ~pos1 & (up_a < -D);
    const D4 d1_pos = lo_b < lo_a ? splat(shrink) * ((lo_a - D) / (lo_a - lo_b) * w) : w;
    const D4 d1_low = up_b > up_a ? splat(shrink) * ((-D - up_a) / (up_b - up_a) * w) : w;
    d1 = sel ? (pos1 ? d1_pos : (low1 ? d1_low : splat(-1))) : d1;
    neg1 = sel ? low1 : neg1;
    const M4 pos2 = lo_b > D, low2 = ~pos2 & (up_b < -D);
    const D4 d2_pos = lo_a < lo_b ? splat(shrink) * ((lo_b - D) / (lo_b - lo_a) * w) : w;
    const D4 d2_low = up_a > up_b ? splat(shrink) * ((-D - up_b) / (up_a - up_b) * w) : w;
    d2 = sel ? (pos2 ? d2_pos : (low2 ? d2_low : splat(-1))) : d2;
    neg2 = sel ? low2 : neg2;
  }

  // bisect_wave's enclose at t.
  RAYFARM_LANES void enclose(D4 t, D4& c, D4& rad) const {
    const D4 lambda = (t - A) / (B - A);
    c = cA + (cB - cA) * lambda;
    rad =
        splat(slack) * ((splat(1) - lambda) * rA + lambda * rB + splat(4 * u) * (rA + rB) +
                        splat(8 * u) * (abs4(cA) + abs4(cB)) + splat(4) * m2_8 * (t - A) * (B - t));
  }

  // An end `x` of the bracket reached by a certain sign, in the lanes of `sel` (x != A and
  // not evaluated there): the lines' enclosure, or f where that is wider than 4 E.
  RAYFARM_LANES void renew_end(M4 sel, D4 x, D4& c, D4& rad, D4& evaluated) {
    D4 c_new, rad_new;
    enclose(x, c_new, rad_new);
    const D4 e = error(x);
    c = sel ? c_new : c;
    rad = sel ? rad_new : rad;
    const M4 wide = sel & ~(rad <= splat(4) * e);
    if (!any(wide)) return;
    const D4 fx = r.f(x, mask_bits(wide));
    c = wide ? fx : c;
    rad = wide ? e : rad;
    evaluated = wide ? x : evaluated;
  }

  // One midpoint in every lane still going; false when none is.
  RAYFARM_LANES bool step() {
    const D4 m = splat(0.5) * (a + b);
    going &= strictly_inside(m, a, b);
    if (!any(going)) return false;
    const M4 open = going & ~plain;
    M4 in1 = open & (m - A < d1);
    M4 in2 = open & ~in1 & (B - m < d2);
    M4 unsure = open & ~in1 & ~in2;
    M4 eval_plain = going & plain, eval_here = M4{0, 0, 0, 0};
    if (any(unsure)) {
      const M4 moved = unsure & ((a != A) | (b != B));
      if (any(moved)) {
        const M4 at_a = moved & (a != A) & (a != Aeval), at_b = moved & (b != B) & (b != Beval);
        if (any(at_a)) renew_end(at_a, a, ca, ra, Aeval);
        if (any(at_b)) renew_end(at_b, b, cb, rb, Beval);
        derive(moved);
      }
      const M4 in1_now = unsure & (m - A < d1);
      const M4 in2_now = unsure & ~in1_now & (B - m < d2);
      in1 |= in1_now;
      in2 |= in2_now;
      const M4 still = unsure & ~in1_now & ~in2_now;
      const M4 to_plain = still & ~(d1 + d2 > splat(0.5) * (b - a));
      plain |= to_plain;
      eval_plain |= to_plain;
      eval_here = still & ~to_plain;
    }
    // Certain lanes: the region's sign.
    const M4 certain = in1 | in2;
    const M4 neg_m = in1 ? neg1 : neg2;
    const M4 up = certain & (neg_a == neg_m);
    a = up ? m : a;
    b = (certain & ~up) ? m : b;
    const M4 evaluate = eval_plain | eval_here;
    if (any(evaluate)) {
      const D4 fm = r.f(m, mask_bits(evaluate));
      const M4 up_e = evaluate & (neg_a == (fm <= 0)), down_e = evaluate & ~up_e;
      a = up_e ? m : a;
      b = down_e ? m : b;
      // Evaluated by the certified search: that end keeps f there and its error.
      const M4 up_h = up_e & eval_here, down_h = down_e & eval_here;
      if (any(eval_here)) {
        const D4 e = error(m);
        ca = up_h ? fm : ca, ra = up_h ? e : ra, Aeval = up_h ? m : Aeval;
        cb = down_h ? fm : cb, rb = down_h ? e : rb, Beval = down_h ? m : Beval;
      }
    }
    return true;
  }
};

[[gnu::target("avx2")]] void bisect_waves(int surfer, const RevsurfRay* rays,
                                          const Bracket* brackets, int total, double* out) {
  for (int at = 0; at < total; at += 4) {
    WaveBisection x;
    x.begin(surfer, rays, brackets, total, at);
    for (int k = 0; k < 200 && x.step(); ++k) {
    }
    x.finish(brackets, out);
  }
}

}  // namespace

bool lanes_available() {
  static const bool available = __builtin_cpu_supports("avx2");
  return available;
}

void crossings_in_lanes(int surfer, double height, const RevsurfRay* rays, int n, double* out) {
  for (int base = 0; base < n; base += kChunk) {
    const int count = std::min(kChunk, n - base);
    int ray[kChunk];
    SearchSpan spans[kChunk];
    Bracket brackets[kChunk];
    int searched = 0;
    for (int i = base; i < base + count; ++i) {
      if (search_span(surfer, height, rays[i], spans[searched]))
        ray[searched++] = i;
      else
        out[i] = -1;
    }
    const int found = step_in_lanes(surfer, rays, ray, spans, searched, out, brackets);
    if (surfer == 1)
      bisect_cones(rays, brackets, found, out);
    else
      bisect_waves(surfer, rays, brackets, found, out);
  }
}

#else

bool lanes_available() { return false; }
void crossings_in_lanes(int, double, const RevsurfRay*, int, double*) {}

#endif

}  // namespace revsurf_detail

void revsurf_first_crossings(int surfer, double height, std::span<const RevsurfRay> rays,
                             std::span<double> out) {
  const int n = static_cast<int>(rays.size());
  if (revsurf_detail::lanes_available()) {
    revsurf_detail::crossings_in_lanes(surfer, height, rays.data(), n, out.data());
    for (int i = 0; i < n; ++i)  // the rare bracket the lanes left (NaN): first_crossing's
      if (std::isnan(out[i])) out[i] = revsurf_first_crossing(surfer, height, rays[i], false);
    return;
  }
  for (int i = 0; i < n; ++i) out[i] = revsurf_first_crossing(surfer, height, rays[i], false);
}

}  // namespace rayfarm
