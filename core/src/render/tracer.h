// The classic Whitted tracer of the lecture (SPEC §3): closest hit, ambient over travelled
// distance, diffuse and Phong/Blinn highlight over light distance, shadows, clamped mirror
// reflection. Iterative, so deep recursion cannot overflow the stack.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "render/prepared_scene.h"

namespace rayfarm {

struct RayCounts {
  std::uint64_t primary = 0;
  std::uint64_t shadow = 0;
  std::uint64_t reflection = 0;
};

template <class T>
inline T clamp01(T x) {  // NaN maps to 0: no NaN can ever reach a pixel
  return x > 0 ? (x < 1 ? x : T(1)) : T(0);
}

template <class T>
inline Vec3<T> clamp01(const Vec3<T>& c) {
  return {clamp01(c.x), clamp01(c.y), clamp01(c.z)};
}

// The object a secondary ray leaves from. Leaving a convex object's outside, the ray cannot
// hit it again; leaving a sphere's inside, it can only hit the far side. This replaces the
// usual epsilon offset, which fails at some scene scale.
struct Origin {
  int object = -1;  // spheres first, then planes; -1 for the eye
  bool inside = false;
};

// Where a ray leaving `from` meets sphere `index`, or a value that is not > 0. The one
// sphere test of both the loop and the hierarchy, so the two agree to the bit.
template <class T>
[[gnu::always_inline, gnu::flatten]] inline T sphere_t(const Vec3<T>& o, const Vec3<T>& d,
                                                       const Vec3<T>& centre, T radius, int index,
                                                       Origin from) {
  const bool own = index == from.object;
  if (own && !from.inside) return T(-1);
  if (!own && from.object >= 0) {
    // A secondary ray that starts on this sphere too (a coincident or touching sphere), to
    // within the rounding of |f|^2 - r^2, at any scale: the rule of the ray's own object
    // applies. Leaving it, no hit; entering it, only the far side. (Its near root is no
    // guide: for grazing rays its rounding error is far larger than the scene's.)
    const Vec3<T> f = o - centre;
    const T ff = glm::dot(f, f), rr = radius * radius;
    if (std::abs(ff - rr) <= 32 * std::numeric_limits<T>::epsilon() * (ff + rr)) {
      if (glm::dot(f, d) >= 0) return T(-1);
      auto roots = sphere_roots(o, d, centre, radius);
      return roots ? roots->far : T(-1);
    }
  }
  auto roots = sphere_roots(o, d, centre, radius);
  if (!roots) return T(-1);
  if (own) return roots->far;
  return roots->near > 0 ? roots->near : roots->far;
}

// Distance to a plane, or -1. A secondary ray that starts on the plane (within rounding)
// cannot hit it: it is the ray's own surface or one coincident with it.
template <class T>
[[gnu::always_inline]] inline T plane_t(const Vec3<T>& o, const Vec3<T>& d,
                                        const PreparedPlane<T>& plane, int index, Origin from) {
  if (index == from.object) return T(-1);
  auto t = plane_distance(o, d, plane.normal, plane.point);
  if (!t) return T(-1);
  if (from.object >= 0) {
    const Vec3<T> a = glm::abs(o), b = glm::abs(plane.point);
    const T scale = std::max({a.x, a.y, a.z, b.x, b.y, b.z});
    if (std::abs(glm::dot(plane.normal, plane.point - o)) <=
        32 * std::numeric_limits<T>::epsilon() * scale)
      return T(-1);
  }
  return *t;
}

template <class T>
struct Hit {
  T t = std::numeric_limits<T>::infinity();
  int object = -1;
};

template <class T>
class Tracer {
 public:
  explicit Tracer(const PreparedScene<T>& scene) : s_(scene) {}

  RayCounts counts;

  // The unit direction from the eye through the world point `target` on the screen; none
  // when the two coincide (or the distance overflows).
  std::optional<Vec3<T>> primary_direction(const Vec3<T>& target) const {
    Vec3<T> dir = target - s_.eye;
    T len = glm::length(dir);
    if (!(len > 0) || !std::isfinite(len)) return std::nullopt;
    return dir / len;
  }

  // Colour of the primary ray through the world point `target` on the screen.
  Vec3<T> primary(const Vec3<T>& target) {
    ++counts.primary;
    std::optional<Vec3<T>> dir = primary_direction(target);
    return dir ? trace(s_.eye, *dir, nullptr) : s_.background;
  }

  // Colour of the primary ray along `dir` (from primary_direction) whose closest hit is
  // already known (as closest() would give it).
  Vec3<T> primary(const Vec3<T>& dir, const Hit<T>& first) {
    ++counts.primary;
    return trace(s_.eye, dir, &first);
  }

  // The nearest hit with 0 < t <= t_max; of equal t, the lowest object index (spheres
  // before planes). The hierarchy, when there is one, gives exactly the loop's answer.
  Hit<T> closest(const Vec3<T>& o, const Vec3<T>& d, Origin from, T t_max) const {
    // Planes first: a sphere beyond the nearest plane cannot be the answer, so the plane's t
    // bounds the sphere search (a sphere at exactly that t still wins: lower index).
    Hit<T> plane;
    closest_plane(o, d, from, t_max, plane);
    if (plane.object >= 0) t_max = plane.t;
    Hit<T> best;
    BvhRay ray;
    if (!s_.bvh.empty() && ray.init(o, d, s_.bvh.scale)) {
      const BvhSphere<T>* spheres = s_.bvh_spheres.data();
      bvh_closest(s_.bvh, ray, float_limit_up(t_max), [&](std::int32_t first, std::int32_t count) {
        for (const BvhSphere<T>* sp = spheres + first; sp != spheres + first + count; ++sp) {
          const T t = sphere_t(o, d, sp->centre, sp->radius, sp->index, from);
          if (t > 0 && t <= t_max && (t < best.t || (t == best.t && sp->index < best.object)))
            best = {t, sp->index};
        }
        return float_limit_up(best.t < t_max ? best.t : t_max);
      });
    } else {
      const int ns = static_cast<int>(s_.spheres.size());
      for (int i = 0; i < ns; ++i) {
        const PreparedSphere<T>& sp = s_.spheres[i];
        const T t = sphere_t(o, d, sp.centre, sp.radius, i, from);
        if (t > 0 && t <= t_max && t < best.t) best = {t, i};
      }
    }
    return best.object >= 0 ? best : plane;
  }

  // Lets the nearest plane with 0 < t <= t_max take best's place if it is nearer.
  void closest_plane(const Vec3<T>& o, const Vec3<T>& d, Origin from, T t_max,
                     Hit<T>& best) const {
    const int ns = static_cast<int>(s_.spheres.size());
    for (int j = 0; j < static_cast<int>(s_.planes.size()); ++j) {
      const T t = plane_t(o, d, s_.planes[j], ns + j, from);
      if (t > 0 && t <= t_max && t < best.t) best = {t, ns + j};
    }
  }

  // Whether anything lies at 0 < t < dist. Planes first: they are few and often block.
  // `last_blocker` (optional) names a sphere to try first and learns the one that blocked:
  // neighbouring shadow rays to one light are usually blocked by the same sphere. It can
  // only make the answer come sooner, never change it. `light` (optional) is the buffer of
  // the light at o + dist * d, for a shadow ray that ends there.
  bool occluded(const Vec3<T>& o, const Vec3<T>& d, Origin from, T dist,
                int* last_blocker = nullptr, const LightBuffer* light = nullptr) const {
    // The cell first: its entries load while the planes and the last blocker are tested.
    LightBuffer::Cell cell;
    const bool buffered = light && light->lookup(glm::dvec3(o), cell);
    const int ns = static_cast<int>(s_.spheres.size());
    for (int j = 0; j < static_cast<int>(s_.planes.size()); ++j) {
      const T t = plane_t(o, d, s_.planes[j], ns + j, from);
      if (t > 0 && t < dist) return true;
    }
    auto blocks = [&](int i) {
      const PreparedSphere<T>& sp = s_.spheres[i];
      const T t = sphere_t(o, d, sp.centre, sp.radius, i, from);
      return t > 0 && t < dist;
    };
    if (last_blocker && *last_blocker >= 0 && blocks(*last_blocker)) return true;
    if (buffered) {
      for (std::int32_t i : light->around)
        if (blocks(i)) return remember(last_blocker, i);
      for (const LightBufferEntry* e = cell.begin; e != cell.end; ++e) {
        const double near = e->near;  // > 0: spheres about the light are not in cells
        if (near * near > cell.limit_sq) break;  // nearest first: none further can block
        if (blocks(e->sphere)) return remember(last_blocker, e->sphere);
      }
      return false;
    }
    BvhRay ray;
    if (!s_.bvh.empty() && ray.init(o, d, s_.bvh.scale)) {
      const BvhSphere<T>* spheres = s_.bvh_spheres.data();
      return bvh_any(
          s_.bvh, ray, float_limit_up(dist), [&](std::int32_t first, std::int32_t count) {
            for (const BvhSphere<T>* sp = spheres + first; sp != spheres + first + count; ++sp) {
              const T t = sphere_t(o, d, sp->centre, sp->radius, sp->index, from);
              if (t > 0 && t < dist) return remember(last_blocker, sp->index);
            }
            return false;
          });
    }
    for (int i = 0; i < ns; ++i)
      if (blocks(i)) return true;
    return false;
  }

 private:
  static bool remember(int* last_blocker, int sphere) {
    if (last_blocker) *last_blocker = sphere;
    return true;
  }

  struct Level {
    Vec3<T> local;
    Vec3<T> weight;  // the material's specular: how much of the next level is added
  };

  // `first`, when given, is the closest hit of the first ray.
  Vec3<T> trace(Vec3<T> origin, Vec3<T> dir, const Hit<T>* first) {
    levels_.clear();
    Origin from;
    T travelled = 0;
    T path_weight = 1;
    for (int depth = 0;; ++depth) {
      Hit<T> hit =
          depth == 0 && first ? *first : closest(origin, dir, from, s_.max_dist - travelled);
      if (hit.object < 0) {
        levels_.push_back({s_.background, Vec3<T>(0)});
        break;
      }
      const T r_total = travelled + hit.t;
      const Vec3<T> p = origin + hit.t * dir;
      Vec3<T> n;
      int material;
      const int ns = static_cast<int>(s_.spheres.size());
      if (hit.object < ns) {
        const PreparedSphere<T>& sp = s_.spheres[hit.object];
        n = p - sp.centre;
        T nl = glm::length(n);
        n = nl > 0 ? n / nl : -dir;
        material = sp.material;
      } else {
        const PreparedPlane<T>& pl = s_.planes[hit.object - ns];
        n = pl.normal;
        material = pl.material;
      }
      // Two-sided: the normal faces the incoming ray; from inside a sphere it points inward.
      const bool inside = glm::dot(n, dir) > 0;
      if (inside) n = -n;
      const PreparedMaterial<T>& m = s_.materials[material];

      Vec3<T> colour = m.ambient / r_total;
      if (s_.features.lights) add_direct_light(colour, p, n, dir, m, {hit.object, inside});
      colour = clamp01(colour);

      const bool reflect = s_.features.reflection && m.reflects && depth < s_.max_depth &&
                           !(path_weight * m.max_specular < s_.bailout);
      if (!reflect) {
        levels_.push_back({colour, Vec3<T>(0)});
        break;
      }
      levels_.push_back({colour, m.specular});
      path_weight *= m.max_specular;
      dir = dir - (2 * glm::dot(n, dir)) * n;
      origin = p;
      travelled = r_total;
      from = {hit.object, inside};
      ++counts.reflection;
    }
    Vec3<T> c = levels_.back().local;
    for (size_t i = levels_.size() - 1; i-- > 0;)
      c = clamp01(levels_[i].local + levels_[i].weight * c);
    return c;
  }

  // Adds each light's term in scene order, as the formula reads.
  void add_direct_light(Vec3<T>& colour, const Vec3<T>& p, const Vec3<T>& n, const Vec3<T>& dir,
                        const PreparedMaterial<T>& m, Origin from) {
    const Vec3<T> v = -dir;
    const Vec3<T> ap = glm::abs(p);
    const T point_scale = std::max({ap.x, ap.y, ap.z});
    if (blockers_.size() != s_.lights.size()) blockers_.assign(s_.lights.size(), -1);
    const bool remember = !s_.bvh.empty();  // small scenes: just loop
    for (std::size_t i = 0; i < s_.lights.size(); ++i) {
      const PreparedLight<T>& light = s_.lights[i];
      int* last_blocker = remember ? &blockers_[i] : nullptr;
      const LightBuffer* light_buffer =
          i < s_.light_buffers.size() && !s_.light_buffers[i].empty() ? &s_.light_buffers[i]
                                                                       : nullptr;
      Vec3<T> l = light.location - p;
      T r = glm::length(l);
      // A light exactly at the shaded point has no direction: it contributes nothing.
      if (!(r > 0) || !std::isfinite(r)) continue;
      l /= r;
      T n_dot_l = glm::dot(n, l);
      // Near 0 the sign of N.L is the rounding noise of L = Lp - p (a light in the surface's
      // own plane): it would switch the light and its highlight on and off pixel by pixel.
      const T noise = 8 * std::numeric_limits<T>::epsilon() * (light.scale + point_scale) / r;
      if (!(n_dot_l > noise)) continue;
      const Vec3<T> e = light.emissivity / r;
      // A material lights cannot change gets exact zeros, unless E/r overflowed (then the
      // NaN it makes must appear exactly as in the general path).
      if (!m.lit && std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z)) continue;
      if (s_.features.shadows) {
        ++counts.shadow;
        // A surface through the light itself (a light placed on an object) is not in the
        // way: hits within the rounding noise of the light's position do not block.
        if (occluded(p, l, from, r - 4 * noise * r, last_blocker, light_buffer)) continue;
      }
      Vec3<T> term = m.diffuse * n_dot_l;
      if (s_.features.highlight && m.highlights) {
        T base;
        if (s_.blinn) {
          Vec3<T> h = l + v;
          T hl = glm::length(h);
          base = hl > 0 ? glm::dot(n, h / hl) : T(0);
        } else {
          Vec3<T> rl = (2 * n_dot_l) * n - l;
          base = glm::dot(rl, v);
        }
        term += m.specular * std::pow(base > 0 ? base : T(0), m.shininess);
      }
      colour += e * term;
    }
  }

  const PreparedScene<T>& s_;
  std::vector<Level> levels_;
  std::vector<int> blockers_;  // per light: the sphere that blocked its last shadow ray
};

}  // namespace rayfarm
