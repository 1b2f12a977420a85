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
#include <vector>

#include "geometry/revsurf.h"
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

// The largest |coordinate| of v.
template <class T>
[[gnu::always_inline]] inline T largest_coordinate(const Vec3<T>& v) {
  const Vec3<T> a = glm::abs(v);
  return std::max({a.x, a.y, a.z});
}

template <class T>
struct PreparedShape {
  enum Kind : std::uint8_t { finite_plane, tex_plane, triangle, revsurf } kind = finite_plane;
  int material = 0;
  // The planar kinds: a unit normal and a frame (u along xdir's part in the plane, v = n × u)
  // with its origin at `point`, and the largest |coordinate| of `point` (plane_ahead_t).
  Vec3<T> normal{0}, point{0}, u{0}, v{0};
  T point_scale = 0;
  T width = 0, height = 0;
  // triangle: its vertices in that frame
  std::array<T, 3> tx{}, ty{};
  // tex_plane
  const Image* texture = nullptr;
  int mode = 0;
  T pixel_w = 1, pixel_h = 1;  // mode 1: a texel's size in the world
  // revsurf: the axis through `point` along the unit `normal`, from 0 to `height`
  int surfer = 1;
  // revsurf: a sphere around the part of its cylinder that exists (revsurf_t's first test)
  glm::dvec3 bound_centre{0};
  double bound_radius = std::numeric_limits<double>::infinity();
};

// Frame coordinates of p on a planar shape.
template <class T>
inline void frame_coords(const PreparedShape<T>& s, const Vec3<T>& p, T& qx, T& qy) {
  const Vec3<T> q = p - s.point;
  qx = glm::dot(s.u, q);
  qy = glm::dot(s.v, q);
}

// A shadow ray's question to a crossing t, as the tracer asks it (t rounded to T, then
// 0 < t < dist), put to the stepping's brackets (revsurf_detail::first_crossing's limit):
// every crossing in (t, next] passes when t rounds above 0 and next below dist, and none
// beyond t does once t rounds to dist or more (rounding is monotone).
template <class T>
struct ShadowLimit {
  T dist;
  bool reached(double t) const { return !(static_cast<T>(t) < dist); }
  bool before(double t, double next) const {
    return static_cast<T>(t) > 0 && static_cast<T>(next) < dist;
  }
};

// The ray in surface s's frame (geometry/revsurf.h), or false when it certainly passes wide
// of the surface or the surface lies behind it. Most rays do: said in world space, before
// the change of frame and the search. The sphere is widened by 2^-20 of the distances
// involved, far more than the rounding of this test and of the search together, so it never
// drops a crossing the search would find; lengths far from 1 skip it.
template <class T>
[[gnu::always_inline]] inline bool revsurf_frame_ray(const PreparedShape<T>& s, const Vec3<T>& o,
                                                     const Vec3<T>& d, RevsurfRay& ray) {
  const glm::dvec3 dd(d);
  {
    const glm::dvec3 oc = s.bound_centre - glm::dvec3(o);
    const double occ = glm::dot(oc, oc), ddd = glm::dot(dd, dd);
    if (occ < 1e100 && ddd > 1e-100 && ddd < 1e100) {
      const double rm = s.bound_radius + 0x1p-20 * (std::sqrt(occ) + s.bound_radius);
      const glm::dvec3 x = glm::cross(oc, dd);
      const double along = glm::dot(oc, dd);
      if (glm::dot(x, x) > rm * rm * ddd || (along < 0 && along * along > rm * rm * ddd))
        return false;
    }
  }
  const glm::dvec3 a(s.normal), q = glm::dvec3(o) - glm::dvec3(s.point);
  const double y0 = glm::dot(q, a), dy = glm::dot(dd, a);
  const glm::dvec3 r0 = q - y0 * a, rd = dd - dy * a;
  ray = {y0, dy, glm::dot(r0, r0), glm::dot(r0, rd), glm::dot(rd, rd)};
  return true;
}

// First t > 0 where the ray meets the surface of revolution (geometry/revsurf.h). Leaving
// the surface itself (`own`), the crossing it starts on is not one: only a later crossing to
// the other side counts, so no offset is needed at any scale. With a ShadowLimit, a value
// that its test answers as it would the crossing.
template <class T, class Limit = revsurf_detail::NoLimit>
T revsurf_t(const PreparedShape<T>& s, const Vec3<T>& o, const Vec3<T>& d, bool own,
            const Limit& limit = {}) {
  RevsurfRay ray;
  if (!revsurf_frame_ray(s, o, d, ray)) return T(-1);
  const double t = revsurf_first_crossing(s.surfer, static_cast<double>(s.height), ray, own, limit);
  return t > 0 ? static_cast<T>(t) : T(-1);
}

// revsurf_t of many rays at one surface, none leaving it, without a limit: the same answers,
// the search done for all of them at once (revsurf_first_crossings). add() each ray with
// the key to give back with its answer, then run().
template <class T, class Key>
class RevsurfBatch {
 public:
  void add(const PreparedShape<T>& s, const Vec3<T>& o, const Vec3<T>& d, Key key) {
    RevsurfRay ray;
    if (!revsurf_frame_ray(s, o, d, ray)) return;  // no crossing: -1, which changes nothing
    rays_.push_back(ray);
    keys_.push_back(key);
  }
  // Drops the rays added and not run.
  void clear() {
    rays_.clear();
    keys_.clear();
  }
  // Calls f(key, t) for each ray added, t as revsurf_t gives it, and empties the batch.
  template <class F>
  void run(const PreparedShape<T>& s, F&& f) {
    if (rays_.empty()) return;
    out_.resize(rays_.size());
    revsurf_first_crossings(s.surfer, static_cast<double>(s.height), rays_, out_);
    for (std::size_t i = 0; i < rays_.size(); ++i)
      f(keys_[i], out_[i] > 0 ? static_cast<T>(out_[i]) : T(-1));
    rays_.clear();
    keys_.clear();
  }

 private:
  std::vector<RevsurfRay> rays_;
  std::vector<Key> keys_;
  std::vector<double> out_;
};

// Distance to the plane through `point` with unit normal n, ahead of a ray from o, or -1.
// A secondary ray that starts in the plane (within rounding) cannot meet it: it is the ray's
// own surface or a coplanar neighbour. `point_scale`: largest_coordinate(point), kept by the
// preparation. Planes and every planar shape use it.
template <class T>
[[gnu::always_inline]] inline T plane_ahead_t(const Vec3<T>& o, const Vec3<T>& d, const Vec3<T>& n,
                                              const Vec3<T>& point, T point_scale, bool secondary) {
  T num;
  const T t = plane_distance_ahead(o, d, n, point, &num);
  if (!(t > 0)) return T(-1);
  if (secondary) {
    const T scale = std::max(largest_coordinate(o), point_scale);
    if (std::abs(num) <= 32 * std::numeric_limits<T>::epsilon() * scale) return T(-1);
  }
  return t;
}

// Where a ray leaving `from` meets shape `index` (its object number), or a value not > 0.
// `shadow` (optional): for a shadow ray to a light that far, only whether the answer lies in
// (0, *shadow) has to be right.
template <class T>
T shape_t(const PreparedShape<T>& s, const Vec3<T>& o, const Vec3<T>& d, int index, Origin from,
          const T* shadow = nullptr) {
  if (s.kind == PreparedShape<T>::revsurf)
    return shadow ? revsurf_t(s, o, d, index == from.object, ShadowLimit<T>{*shadow})
                  : revsurf_t(s, o, d, index == from.object);
  if (index == from.object) return T(-1);  // flat: never met again by a ray leaving it
  const T t = plane_ahead_t(o, d, s.normal, s.point, s.point_scale, from.object >= 0);
  if (!(t > 0)) return T(-1);
  T qx, qy;
  frame_coords(s, o + t * d, qx, qy);
  if (s.kind == PreparedShape<T>::triangle) {
    int pos = 0, neg = 0;
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      const T side = (s.tx[j] - s.tx[i]) * (qy - s.ty[i]) - (s.ty[j] - s.ty[i]) * (qx - s.tx[i]);
      pos += side > 0;
      neg += side < 0;
    }
    return pos > 0 && neg > 0 ? T(-1) : t;
  }
  return qx >= 0 && qx <= s.width && qy >= 0 && qy <= s.height ? t : T(-1);
}

// The outward normal at p (before it is turned to face the ray).
template <class T>
Vec3<T> shape_normal(const PreparedShape<T>& s, const Vec3<T>& p) {
  if (s.kind != PreparedShape<T>::revsurf) return s.normal;
  const Vec3<T> q = p - s.point;
  const T y = glm::dot(q, s.normal);
  double slope;
  const T r = static_cast<T>(revsurf_radius(s.surfer, static_cast<double>(y), &slope));
  // The gradient of |radial|² − r², halved.
  const Vec3<T> n = (q - y * s.normal) - (r * static_cast<T>(slope)) * s.normal;
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
    // Clamped as floating point first: a coordinate may be huge or not finite.
    auto index = [](T q, T size, int n) {
      const T i = std::floor(q / size * static_cast<T>(n));
      return i > 0 ? (i < static_cast<T>(n - 1) ? static_cast<long long>(i) : n - 1LL) : 0LL;
    };
    tx = index(qx, s.width, img.width);
    ty = index(qy, s.height, img.height);
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
