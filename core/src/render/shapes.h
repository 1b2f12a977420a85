// The bounded shapes other than spheres, in the lecture profile's arithmetic (precision T):
// finite and textured planes, triangles, surfaces of revolution. Each has its hit test with
// its own-surface rule, its bounds, its normal and what it changes of the material.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "rayfarm/image.h"
#include "rayfarm/intersect.h"

namespace rayfarm {

// The object a secondary ray leaves from: `inside` is the side of its surface the new ray
// starts on (into a sphere: true). Leaving a convex object's outside, the ray cannot hit it
// again; leaving a sphere's inside, it can only hit the far side. This replaces the usual
// epsilon offset, which fails at some scene scale.
struct Origin {
  int object = -1;  // spheres, then planes, then other shapes; -1 for the eye
  bool inside = false;
};

template <class T>
struct PreparedShape {
  enum Kind : std::uint8_t { finite_plane, tex_plane, triangle, revsurf } kind = finite_plane;
  int material = 0;
  // The planar kinds: a unit normal and a frame (u along xdir's part in the plane, v = n × u)
  // with its origin at `point`.
  Vec3<T> normal{0}, point{0}, u{0}, v{0};
  T width = 0, height = 0;
  // triangle: its vertices in that frame
  std::array<T, 3> tx{}, ty{};
  // tex_plane
  const Image* texture = nullptr;
  int mode = 0;
  T pixel_w = 1, pixel_h = 1;  // mode 1: a texel's size in the world
  // revsurf: the axis through `point` along the unit `normal`, from 0 to `height`
  int surfer = 1;
};

// Radius r(y) of a course profile and its slope: 1 the cone 4 − 2y/3, 2 and 3 waves.
template <class T>
T profile_radius(int surfer, T y, T* slope = nullptr) {
  switch (surfer) {
    case 1:
      if (slope) *slope = T(-2) / 3;
      return 4 - T(2) / 3 * y;
    case 2:
      if (slope) *slope = T(-0.5) * std::sin(y);
      return 1 + T(0.5) * std::cos(y);
    default:
      if (slope) *slope = T(0.5) * std::cos(y);
      return 1 + T(0.5) * std::sin(y);
  }
}

template <class T>
T profile_max_radius(int surfer) {
  return surfer == 1 ? T(4) : T(1.5);
}

// Frame coordinates of p on a planar shape.
template <class T>
inline void frame_coords(const PreparedShape<T>& s, const Vec3<T>& p, T& qx, T& qy) {
  const Vec3<T> q = p - s.point;
  qx = glm::dot(s.u, q);
  qy = glm::dot(s.v, q);
}

// First t > 0 (and <= t_max) where the ray meets the surface of revolution. Leaving the
// surface itself (`own`), the crossing it starts on is not one: only a later crossing of
// |radial|² − r(y)² to the other side counts, so no offset is needed at any scale.
template <class T>
T revsurf_t(const PreparedShape<T>& s, const Vec3<T>& o, const Vec3<T>& d, bool own) {
  using L = long double;  // the root search needs more than float
  const Vec3<L> a(s.normal), q = Vec3<L>(o) - Vec3<L>(s.point), dd(d);
  const L y0 = glm::dot(q, a), dy = glm::dot(dd, a);
  const Vec3<L> r0 = q - y0 * a, rd = dd - dy * a;
  const L rr = glm::dot(r0, r0), rdd = glm::dot(rd, rd), r0d = glm::dot(r0, rd);
  const L h = s.height;
  auto f = [&](L t) {
    const L r = profile_radius<L>(s.surfer, y0 + t * dy);
    return rr + 2 * t * r0d + t * t * rdd - r * r;
  };
  L lo = 0, hi = std::numeric_limits<L>::infinity();
  if (dy != 0) {
    L t1 = -y0 / dy, t2 = (h - y0) / dy;
    if (t1 > t2) std::swap(t1, t2);
    lo = std::max(lo, t1);
    hi = std::min(hi, t2);
  } else if (y0 < 0 || y0 > h) {
    return T(-1);
  }
  const L rmax = profile_max_radius<L>(s.surfer);
  if (rdd > 0) {
    const L disc = r0d * r0d - rdd * (rr - rmax * rmax);
    if (disc < 0) return T(-1);
    const L root = std::sqrt(disc);
    lo = std::max(lo, (-r0d - root) / rdd);
    hi = std::min(hi, (-r0d + root) / rdd);
  } else if (rr > rmax * rmax) {
    return T(-1);
  }
  if (!(lo < hi) || !std::isfinite(hi)) return T(-1);
  constexpr int kSteps = 1024;
  const L span = hi - lo;
  L prev_t = lo, prev = f(lo);
  bool started = !own;
  for (int i = 1; i <= kSteps; ++i) {
    const L t = lo + span * i / kSteps;
    const L v = f(t);
    // Leaving its own surface the first sample decides the side the ray is on.
    if (!started) {
      started = true;
      prev_t = t;
      prev = v;
      continue;
    }
    if (t > 0 && (prev <= 0) != (v <= 0)) {
      L a0 = std::max<L>(prev_t, 0), b0 = t, fa = f(a0);
      for (int it = 0; it < 96 && a0 < b0; ++it) {
        const L mid = (a0 + b0) / 2;
        if (mid <= a0 || mid >= b0) break;
        const L fm = f(mid);
        if ((fa <= 0) == (fm <= 0)) {
          a0 = mid;
          fa = fm;
        } else {
          b0 = mid;
        }
      }
      if (b0 > 0) return static_cast<T>(b0);
    }
    prev_t = t;
    prev = v;
  }
  return T(-1);
}

// Where a ray leaving `from` meets shape `index` (its object number), or a value not > 0.
template <class T>
T shape_t(const PreparedShape<T>& s, const Vec3<T>& o, const Vec3<T>& d, int index, Origin from) {
  if (s.kind == PreparedShape<T>::revsurf) return revsurf_t(s, o, d, index == from.object);
  if (index == from.object) return T(-1);  // flat: never met again by a ray leaving it
  auto t = plane_distance(o, d, s.normal, s.point);
  if (!t || !(*t > 0)) return T(-1);
  if (from.object >= 0) {
    // A ray that starts in this shape's plane (a coplanar neighbour) cannot hit it.
    const Vec3<T> a = glm::abs(o), b = glm::abs(s.point);
    const T scale = std::max({a.x, a.y, a.z, b.x, b.y, b.z});
    if (std::abs(glm::dot(s.normal, s.point - o)) <= 32 * std::numeric_limits<T>::epsilon() * scale)
      return T(-1);
  }
  T qx, qy;
  frame_coords(s, o + *t * d, qx, qy);
  if (s.kind == PreparedShape<T>::triangle) {
    int pos = 0, neg = 0;
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      const T side = (s.tx[j] - s.tx[i]) * (qy - s.ty[i]) - (s.ty[j] - s.ty[i]) * (qx - s.tx[i]);
      pos += side > 0;
      neg += side < 0;
    }
    return pos > 0 && neg > 0 ? T(-1) : *t;
  }
  return qx >= 0 && qx <= s.width && qy >= 0 && qy <= s.height ? *t : T(-1);
}

// The outward normal at p (before it is turned to face the ray).
template <class T>
Vec3<T> shape_normal(const PreparedShape<T>& s, const Vec3<T>& p) {
  if (s.kind != PreparedShape<T>::revsurf) return s.normal;
  const Vec3<T> q = p - s.point;
  const T y = glm::dot(q, s.normal);
  T slope;
  const T r = profile_radius<T>(s.surfer, y, &slope);
  // The gradient of |radial|² − r², halved.
  const Vec3<T> n = (q - y * s.normal) - (r * slope) * s.normal;
  const T len = glm::length(n);
  return len > 0 ? n / len : s.normal;
}

// The texel factor (0..1 per channel) a textured plane puts on ambient and diffuse at p.
template <class T>
Vec3<T> shape_texel(const PreparedShape<T>& s, const Vec3<T>& p) {
  if (s.kind != PreparedShape<T>::tex_plane || !s.texture || s.texture->width == 0)
    return Vec3<T>(1);
  const Image& img = *s.texture;
  T qx, qy;
  frame_coords(s, p, qx, qy);
  long long tx, ty;
  if (s.mode == 0) {
    tx = static_cast<long long>(std::floor(qx / s.width * img.width));
    ty = static_cast<long long>(std::floor(qy / s.height * img.height));
    tx = std::clamp<long long>(tx, 0, img.width - 1);
    ty = std::clamp<long long>(ty, 0, img.height - 1);
  } else {
    auto wrap = [](T q, T size, int n) {
      const T k = std::floor(q / size);
      if (!std::isfinite(k)) return 0LL;
      const long long i = static_cast<long long>(std::fmod(k, static_cast<T>(n)));
      return i < 0 ? i + n : i;
    };
    tx = wrap(qx, s.pixel_w, img.width);
    ty = wrap(qy, s.pixel_h, img.height);
  }
  const std::uint8_t* t = img.rgb.data() + 3 * ((img.height - 1 - ty) * img.width + tx);
  return Vec3<T>(t[0], t[1], t[2]) / T(255);
}

}  // namespace rayfarm
