// The classic Whitted tracer of the lecture (the lecture profile): closest hit, ambient over
// travelled distance, diffuse and Phong/Blinn highlight over light distance, shadows,
// clamped mirror reflection, and light let through translucent objects. Iterative with an
// explicit list of levels, so deep recursion cannot overflow the stack.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "render/film.h"
#include "render/prepared_scene.h"
#include "render/ray_counts.h"
#include "render/recorder.h"

namespace rayfarm {

template <class T>
inline T clamp01(T x) {  // NaN maps to 0: no NaN can ever reach a pixel
  return x > 0 ? (x < 1 ? x : T(1)) : T(0);
}

template <class T>
inline Vec3<T> clamp01(const Vec3<T>& c) {
  return {clamp01(c.x), clamp01(c.y), clamp01(c.z)};
}

// Where a ray leaving `from` meets sphere `index`, or a value that is not > 0. The one
// sphere test of both the loop and the hierarchy, so the two agree to the bit.
template <class T>
[[gnu::always_inline, gnu::flatten]] inline T sphere_t(const Vec3<T>& o, const Vec3<T>& d,
                                                       const Vec3<T>& centre, T radius, int index,
                                                       Origin from) {
  const bool own = index == from.object;
  if (own && !from.inside) return T(-1);
  // A miss is a miss whichever rule applies below; most tests miss, so this comes first.
  const auto roots = sphere_roots(o, d, centre, radius);
  if (!roots) return T(-1);
  if (!own && from.object >= 0) {
    // A secondary ray that starts on this sphere too (a coincident or touching sphere), to
    // within the rounding of |f|^2 - r^2, at any scale: the rule of the ray's own object
    // applies. Leaving it, no hit; entering it, only the far side. (Its near root is no
    // guide: for grazing rays its rounding error is far larger than the scene's.)
    const Vec3<T> f = o - centre;
    const T ff = glm::dot(f, f), rr = radius * radius;
    if (std::abs(ff - rr) <= 32 * std::numeric_limits<T>::epsilon() * (ff + rr))
      return glm::dot(f, d) >= 0 ? T(-1) : roots->far;
  }
  if (own) return roots->far;
  return roots->near > 0 ? roots->near : roots->far;
}

// floor(log2 |x|) for a normal x; kNotNormal for 0, a subnormal, an infinity or a NaN.
inline constexpr int kNotNormal = std::numeric_limits<int>::max();
template <class T>
inline int binary_exponent(T x) {
  if constexpr (sizeof(T) == 8) {
    const int e = static_cast<int>(__builtin_bit_cast(std::uint64_t, x) >> 52 & 0x7ff);
    return e == 0 || e == 0x7ff ? kNotNormal : e - 1023;
  } else {
    static_assert(sizeof(T) == 4);
    const int e = static_cast<int>(__builtin_bit_cast(std::uint32_t, x) >> 23 & 0xff);
    return e == 0 || e == 0xff ? kNotNormal : e - 127;
  }
}

// Whether adding m.specular · pow(b, m.shininess) to `term` (b >= 0) would certainly leave
// every channel as it is, so the power need not be computed: at shininess 64, any base
// below 1/2 adds less than a rounding to a term near 1. pow(0, s) is 0 for s > 0. For
// b > 0, b < 2^(g+1) with g its binary exponent, so b^s < 2^((g+1) s) < 2^k for the whole k
// below, and the library's power, within an ulp of b^s, is at most 2^k (at least the
// smallest subnormal). Times |specular| < 2^E that is at most 2^(E+k); where that is at most
// a quarter of an ulp of a channel, the rounded sum is the channel again. A channel of -0 (a
// diffuse of -0 is valid) would turn +0 with anything added, +0 too: such a term is left to
// the sum.
template <class T>
inline bool highlight_negligible(const PreparedMaterial<T>& m, T b, const Vec3<T>& term) {
  if (!m.highlight_bounded) return false;
  auto minus_zero = [&](int c) { return term[c] == 0 && std::signbit(term[c]); };
  if (!(b > 0)) return !(minus_zero(0) || minus_zero(1) || minus_zero(2));
  constexpr int kDigits = std::numeric_limits<T>::digits;
  constexpr int kSubnormal = std::numeric_limits<T>::min_exponent - kDigits;  // 2^this: the least
  const int g = binary_exponent(b);
  if (g == kNotNormal || g >= 0) return false;
  const T q = T(g + 1) * m.shininess;  // <= 0, and k > (g+1) s whatever q's rounding
  const int k = q < T(kSubnormal) ? kSubnormal : static_cast<int>(q) + 1;
  for (int c = 0; c < 3; ++c) {
    if (m.specular_exp[c] == PreparedMaterial<T>::kZeroSpecular) {  // adds ±0
      if (minus_zero(c)) return false;
      continue;
    }
    const int t = binary_exponent(term[c]);  // a quarter ulp of term[c] is 2^(t - digits - 1)
    if (t == kNotNormal || t - kDigits - 1 < kSubnormal || m.specular_exp[c] + k > t - kDigits - 1)
      return false;
  }
  return true;
}

// Distance to a plane ahead of the ray, or -1 (plane_ahead_t, shapes.h).
template <class T>
[[gnu::always_inline]] inline T plane_t(const Vec3<T>& o, const Vec3<T>& d,
                                        const PreparedPlane<T>& plane, int index, Origin from) {
  if (index == from.object) return T(-1);
  return plane_ahead_t(o, d, plane.normal, plane.point, plane.point_scale, from.object >= 0);
}

template <class T>
struct Hit {
  T t = std::numeric_limits<T>::infinity();
  int object = -1;

  // The one order of hits: nearer first; at equal t the lower object number (spheres, then
  // planes, then the other shapes). Loops, hierarchies and screen bins all use it.
  bool beaten_by(T t2, int object2) const {
    return t2 < t || (t2 == t && object2 < object);
  }
};

// For a sum s of two whole numbers (floors), 0.5 when it is odd, 0 when it is even, NaN when
// it is not finite: |fmod(s, 2)| / 2, without fmod's library call (every shaded point of a
// tiled plane asks). s / 2 is exact (a whole number or one and a half of one), and so is its
// distance from its floor; at 2^53 and beyond (2^24 in float) every s is even and so is s / 2.
template <class T>
inline T tile_parity(T s) {
  const T half = s * T(0.5);
  return half - std::floor(half);
}

// With kRecord, a tracer can write each path it traces to a recorder (explain.cpp); a
// render's tracer has none of that code compiled in.
template <class T, bool kRecord = false>
class Tracer {
 public:
  explicit Tracer(const PreparedScene<T>& scene) : s_(scene) {}

  RayCounts counts;

  // From now on each traced path is written to `recorder` (cleared by the caller per
  // sample); null: none is.
  void record(Recorder* recorder) requires kRecord { rec_ = recorder; }

  // For a pipeline whose samples each become their pixel's byte through `film` (one sample a
  // pixel): from now on, where the scene allows it (Features::byte_cutoff), a path stops
  // once its byte is settled (byte_settled), and the colour returned is one with that byte.
  void stop_at_settled_bytes(const Film& film) requires(!kRecord) {
    settle_ = s_.features.byte_cutoff;
    film_ = film;
    // With translucent objects, the heaviest of the rays still to follow goes first, so that
    // the light ones are the last left and can be left out. Where no path can reach the
    // budget of levels (its every level with two children down to max_depth), the order
    // changes no level's value; elsewhere the budget makes it matter, and the order stays.
    best_first_ = settle_ && s_.features.transparency && s_.max_depth >= 0 &&
                  s_.max_depth < 14 && (std::size_t{2} << s_.max_depth) <= kMaxBranchingLevels;
  }

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
    if (!dir && recording()) {
      const int h = rec_->begin(RecordedHit::Ray::primary, -1, 0);
      rec_->hits[h].origin = triple(s_.eye);
      rec_->hits[h].value = triple(s_.background);
    }
    return dir ? trace(s_.eye, *dir, nullptr) : s_.background;
  }

  // Colour of the primary ray along `dir` (from primary_direction) whose closest hit is
  // already known (as closest() would give it), and, if `bounce` is given, the closest hit of
  // the reflection ray that hit sends (as closest() would give it for primary_bounce's ray).
  Vec3<T> primary(const Vec3<T>& dir, const Hit<T>& first, const Hit<T>* bounce = nullptr) {
    ++counts.primary;
    return trace(s_.eye, dir, &first, bounce);
  }

  // The reflection ray a primary ray along `dir` sends from its closest hit `first`, if it
  // sends one: computed exactly as follow() computes it, with the distance cap it searches to.
  struct Bounce {
    Vec3<T> origin, dir;
    Origin from;
    T t_max;
  };
  std::optional<Bounce> primary_bounce(const Vec3<T>& dir, const Hit<T>& first) const {
    const T travelled = T(0) + first.t;  // follow(): depth 0, path weight 1, travelled 0
    const Vec3<T> p = s_.eye + first.t * dir;
    const Surface sf = surface(first.object, p, dir);
    if (!reflects(*sf.m, 0, T(1), true)) return std::nullopt;
    return Bounce{p, reflected(dir, sf.n), {first.object, sf.inside}, s_.max_dist - travelled};
  }

  // The nearest hit with 0 < t <= t_max, in the order of Hit::beaten_by. The hierarchies,
  // when there are any, give exactly the loops' answer.
  Hit<T> closest(const Vec3<T>& o, const Vec3<T>& d, Origin from, T t_max) const {
    BvhRay ray;
    const bool walk = !s_.bvh.empty() && ray.init(o, d, s_.bvh.scale);
    // Planes (and the other shapes, unless the hierarchy holds them) first: nothing beyond
    // the nearest of them can be the answer, so its t bounds the search (a sphere at exactly
    // that t still wins: lower number).
    Hit<T> plane;
    closest_plane(o, d, from, t_max, plane, !(walk && s_.bvh_shapes));
    if (plane.object >= 0) t_max = plane.t;
    Hit<T> best;
    if (walk) {
      const PreparedSphere<T>* spheres = s_.bvh_spheres.data();
      const std::int32_t* indices = s_.bvh_index.data();
      auto limit = [&] { return float_limit_up(best.t < t_max ? best.t : t_max); };
      auto take = [&](T t, int object) {
        if (t > 0 && t <= t_max && best.beaten_by(t, object)) best = {t, object};
      };
      if (s_.bvh_shapes) {
        const int shape_base = s_.shape_base();
        bvh_closest(s_.bvh, ray, limit(), [&](std::int32_t first, std::int32_t count) {
          for (std::int32_t k = first; k < first + count; ++k) {
            const PreparedSphere<T>& sp = spheres[k];
            const int index = indices[k];
            take(index < shape_base ? sphere_t(o, d, sp.centre, sp.radius, index, from)
                                    : shape_t(s_.shapes[index - shape_base], o, d, index, from),
                 index);
          }
          return limit();
        });
      } else {
        bvh_closest(s_.bvh, ray, limit(), [&](std::int32_t first, std::int32_t count) {
          for (std::int32_t k = first; k < first + count; ++k) {
            const PreparedSphere<T>& sp = spheres[k];
            take(sphere_t(o, d, sp.centre, sp.radius, indices[k], from), indices[k]);
          }
          return limit();
        });
      }
    } else {
      const int ns = static_cast<int>(s_.spheres.size());
      for (int i = 0; i < ns; ++i) {
        const PreparedSphere<T>& sp = s_.spheres[i];
        const T t = sphere_t(o, d, sp.centre, sp.radius, i, from);
        if (t > 0 && t <= t_max && t < best.t) best = {t, i};
      }
    }
    // The nearer, and at equal t the lower number: a shape from the hierarchy at the plane's
    // t loses to it, a sphere wins.
    return best.object >= 0 && (plane.object < 0 || plane.beaten_by(best.t, best.object)) ? best
                                                                                          : plane;
  }

  // Lets the nearest plane or (with `shapes`) other shape with 0 < t <= t_max take best's
  // place if it comes first.
  void closest_plane(const Vec3<T>& o, const Vec3<T>& d, Origin from, T t_max, Hit<T>& best,
                     bool shapes = true) const {
    const int base = s_.plane_base();
    for (int j = 0; j < static_cast<int>(s_.planes.size()); ++j) {
      const T t = plane_t(o, d, s_.planes[j], base + j, from);
      if (t > 0 && t <= t_max && t < best.t) best = {t, base + j};
    }
    if (shapes && !s_.shapes.empty()) closest_shape(o, d, from, t_max, best);
  }

  // Whether anything lies at 0 < t < dist. Planes first: they are few and often block.
  // `last_blocker` (optional) names a sphere or other shape (its object number) to try first
  // and learns the one that blocked: neighbouring shadow rays to one light are usually
  // blocked by the same object. It can only make the answer come sooner, never change it.
  // `light` (optional) is the buffer of the light at o + dist * d, for a shadow ray that ends
  // there.
  bool occluded(const Vec3<T>& o, const Vec3<T>& d, Origin from, T dist,
                int* last_blocker = nullptr, const LightBuffer* light = nullptr) const {
    // The cell first: its entries load while the planes and the last blocker are tested.
    LightBuffer::Cell cell;
    const bool buffered = light && light->lookup(glm::dvec3(o), cell);
    const int base = s_.plane_base();
    for (int j = 0; j < static_cast<int>(s_.planes.size()); ++j) {
      const T t = plane_t(o, d, s_.planes[j], base + j, from);
      if (t > 0 && t < dist) return true;
    }
    // Whether sphere `object`, whose record is `sp` (in file order or the hierarchy's), blocks.
    auto sphere_blocks = [&](const PreparedSphere<T>& sp, int object) {
      const T t = sphere_t(o, d, sp.centre, sp.radius, object, from);
      return t > 0 && t < dist;
    };
    auto blocks = [&](int i) { return sphere_blocks(s_.spheres[i], i); };
    if (last_blocker && *last_blocker >= 0) {
      const int last = *last_blocker;
      if (last < base ? blocks(last) : shape_blocks_one(last - s_.shape_base(), o, d, from, dist))
        return true;
    }
    if (buffered) {
      // The buffer lists the spheres and, numbered after them, the other shapes; those the
      // hierarchy holds by their place in it, where blockers_in_leaf_order says so.
      const int ns = static_cast<int>(s_.spheres.size()), shape_base = s_.shape_base();
      const std::int32_t placed =
          s_.blockers_in_leaf_order ? static_cast<std::int32_t>(s_.bvh_index.size()) : 0;
      auto blocker_blocks = [&](std::int32_t i) {
        if (i < placed) {
          const int object = s_.bvh_index[i];
          if (object >= shape_base)
            return shape_blocks_one(object - shape_base, o, d, from, dist) &&
                   remember(last_blocker, object);
          return sphere_blocks(s_.bvh_spheres[i], object) && remember(last_blocker, object);
        }
        return i < ns ? blocks(i) && remember(last_blocker, i)
                      : shape_blocks_one(i - ns, o, d, from, dist) &&
                            remember(last_blocker, shape_base + (i - ns));
      };
      for (std::int32_t i : light->around)
        if (blocker_blocks(i)) return true;
      for (const LightBufferEntry* e = cell.begin; e != cell.end; ++e) {
        const double near = e->near;             // > 0: blockers about the light are not in cells
        if (near * near > cell.limit_sq) break;  // nearest first: none further can block
        if (blocker_blocks(e->blocker)) return true;
      }
      return false;
    }
    BvhRay ray;
    const bool walk = !s_.bvh.empty() && ray.init(o, d, s_.bvh.scale);
    if (!(walk && s_.bvh_shapes) && !s_.shapes.empty() &&
        shape_blocks(o, d, from, dist, last_blocker))
      return true;
    if (walk) {
      const PreparedSphere<T>* spheres = s_.bvh_spheres.data();
      const std::int32_t* indices = s_.bvh_index.data();
      const int shape_base = s_.bvh_shapes ? s_.shape_base() : std::numeric_limits<int>::max();
      return bvh_any(
          s_.bvh, ray, float_limit_up(dist), [&](std::int32_t first, std::int32_t count) {
            for (std::int32_t k = first; k < first + count; ++k) {
              const int index = indices[k];
              if (index >= shape_base) {
                if (shape_blocks_one(index - shape_base, o, d, from, dist))
                  return remember(last_blocker, index);
                continue;
              }
              const T t = sphere_t(o, d, spheres[k].centre, spheres[k].radius, index, from);
              if (t > 0 && t < dist) return remember(last_blocker, index);
            }
            return false;
          });
    }
    const int ns = static_cast<int>(s_.spheres.size());
    for (int i = 0; i < ns; ++i)
      if (blocks(i)) return true;
    return false;
  }

  // How much of a light at distance `dist` along d reaches o: zero behind anything opaque,
  // and filtered once by each translucent object on the way.
  Vec3<T> transmittance(Vec3<T> o, const Vec3<T>& d, Origin from, T dist) const {
    Vec3<T> through(1);
    int crossed[4 * kMaxCrossings];  // every object met: at most one per step
    int n_crossed = 0;
    for (int steps = 0; steps < 4 * kMaxCrossings; ++steps) {
      const Hit<T> hit = closest(o, d, from, dist);
      if (hit.object < 0 || !(hit.t < dist)) return through;
      const PreparedMaterial<T>& m = s_.materials[material_of(hit.object)];
      if (!(m.transparency > 0)) return Vec3<T>(0);
      // An object is one filter, however many of its surfaces the ray crosses.
      bool seen = false;
      for (int i = 0; i < n_crossed; ++i) seen = seen || crossed[i] == hit.object;
      if (!seen) {
        through *= m.filter;
        crossed[n_crossed++] = hit.object;
      }
      const Vec3<T> p = o + hit.t * d;
      from = {hit.object, glm::dot(outward_normal(hit.object, p), d) < 0};
      o = p;
      dist -= hit.t;
    }
    return Vec3<T>(0);  // more crossings than any real scene has: treat as opaque
  }

 private:
  static constexpr int kMaxCrossings = 64;
  // Levels (hits) one primary ray may spawn once transparency lets rays branch.
  static constexpr std::size_t kMaxBranchingLevels = 1 << 14;

  bool recording() const { return kRecord && rec_; }

  static bool remember(int* last_blocker, int object) {
    if (last_blocker) *last_blocker = object;
    return true;
  }

  void closest_shape(const Vec3<T>& o, const Vec3<T>& d, Origin from, T t_max,
                     Hit<T>& best) const {
    const int base = s_.shape_base();
    auto test = [&](int k) {
      const T t = shape_t(s_.shapes[k], o, d, base + k, from);
      if (t > 0 && t <= t_max && best.beaten_by(t, base + k)) best = {t, base + k};
    };
    BvhRay ray;
    if (!s_.shape_bvh.empty() && ray.init(o, d, s_.shape_bvh.scale)) {
      bvh_closest(s_.shape_bvh, ray, float_limit_up(std::min(t_max, best.t)),
                  [&](std::int32_t first, std::int32_t count) {
                    for (std::int32_t i = first; i < first + count; ++i) test(s_.shape_bvh.order[i]);
                    return float_limit_up(best.t < t_max ? best.t : t_max);
                  });
      return;
    }
    for (int k = 0; k < static_cast<int>(s_.shapes.size()); ++k) test(k);
  }

  // Whether shape k (not an object number) lies at 0 < t < dist.
  bool shape_blocks_one(int k, const Vec3<T>& o, const Vec3<T>& d, Origin from, T dist) const {
    const T t = shape_t(s_.shapes[k], o, d, s_.shape_base() + k, from, &dist);
    return t > 0 && t < dist;
  }

  // Whether any shape does; the one that does goes to `last_blocker` (optional).
  bool shape_blocks(const Vec3<T>& o, const Vec3<T>& d, Origin from, T dist,
                    int* last_blocker = nullptr) const {
    const int base = s_.shape_base();
    auto blocks = [&](int k) {
      return shape_blocks_one(k, o, d, from, dist) && remember(last_blocker, base + k);
    };
    BvhRay ray;
    if (!s_.shape_bvh.empty() && ray.init(o, d, s_.shape_bvh.scale))
      return bvh_any(s_.shape_bvh, ray, float_limit_up(dist),
                     [&](std::int32_t first, std::int32_t count) {
                       for (std::int32_t i = first; i < first + count; ++i)
                         if (blocks(s_.shape_bvh.order[i])) return true;
                       return false;
                     });
    for (int k = 0; k < static_cast<int>(s_.shapes.size()); ++k)
      if (blocks(k)) return true;
    return false;
  }

  int material_of(int object) const {
    const int ns = s_.plane_base(), np = static_cast<int>(s_.planes.size());
    if (object < ns) return s_.sphere_materials[object];
    if (object < ns + np) return s_.planes[object - ns].material;
    return s_.shapes[object - ns - np].material;
  }

  // The object's normal at p, pointing out of it (before it is turned towards the ray).
  Vec3<T> outward_normal(int object, const Vec3<T>& p) const {
    const int ns = s_.plane_base(), np = static_cast<int>(s_.planes.size());
    if (object < ns) {
      const Vec3<T> n = p - s_.spheres[object].centre;
      const T len = glm::length(n);
      return len > 0 ? n / len : Vec3<T>(0);
    }
    if (object < ns + np) return s_.planes[object - ns].normal;
    return shape_normal(s_.shapes[object - ns - np], p);
  }

  // What shading needs of a hit: its facing normal, material and the colours there.
  struct Surface {
    Vec3<T> n;
    bool inside;  // the ray arrived from the side the normal does not point to
    const PreparedMaterial<T>* m;
    Vec3<T> ambient, diffuse;
  };

  Surface surface(int object, const Vec3<T>& p, const Vec3<T>& dir) const {
    Surface s;
    const int ns = s_.plane_base(), np = static_cast<int>(s_.planes.size());
    int material;
    std::optional<Vec3<T>> texel;
    const PreparedPlane<T>* tiles = nullptr;
    if (object < ns) {
      const PreparedSphere<T>& sp = s_.spheres[object];
      s.n = p - sp.centre;
      T nl = glm::length(s.n);
      s.n = nl > 0 ? s.n / nl : -dir;
      material = s_.sphere_materials[object];
    } else if (object < ns + np) {
      const PreparedPlane<T>& pl = s_.planes[object - ns];
      s.n = pl.normal;
      material = pl.material;
      if (pl.alt_material >= 0) tiles = &pl;
    } else {
      const PreparedShape<T>& sh = s_.shapes[object - ns - np];
      s.n = shape_normal(sh, p);
      material = sh.material;
      if (sh.kind == PreparedShape<T>::tex_plane) texel = shape_texel(sh, p);
    }
    // Two-sided: the normal faces the incoming ray; from inside a sphere it points inward.
    s.inside = glm::dot(s.n, dir) > 0;
    if (s.inside) s.n = -s.n;
    s.m = &s_.materials[material];
    const PreparedMaterial<T>* colours = s.m;
    if (tiles) {
      const bool odd = tile_is_odd(*tiles, p);
      if (tiles->world_xz) {  // 2009: odd squares take the other ambient colour, nothing else
        s.ambient = (odd ? s_.materials[tiles->alt_material] : *s.m).ambient;
        s.diffuse = s.m->diffuse;
        return s;
      }
      if (!odd) colours = &s_.materials[tiles->alt_material];  // odd: the plane's own
    }
    s.ambient = texel ? colours->ambient * *texel : colours->ambient;
    s.diffuse = texel ? colours->diffuse * *texel : colours->diffuse;
    return s;
  }

  // Whether the square at p has an odd index sum (the course's rule: in the plane's frame,
  // or for the 2009 form on world x and z offset by 10000). A sum that is not finite counts
  // as odd in the 2009 form and even otherwise (tile_parity).
  static bool tile_is_odd(const PreparedPlane<T>& pl, const Vec3<T>& p) {
    T ix, iy;
    if (pl.world_xz) {
      ix = std::floor((p.x + 10000) / pl.tile_w);
      iy = std::floor((p.z + 10000) / pl.tile_h);
      return tile_parity(ix + iy) != 0;
    }
    ix = std::floor(glm::dot(pl.u, p) / pl.tile_w);
    iy = std::floor(glm::dot(pl.v, p) / pl.tile_h);
    return tile_parity(ix + iy) == T(0.5);
  }

  // What a level's reflected or transmitted field holds when it names no level.
  static constexpr int kNone = -1;      // no such ray
  static constexpr int kPending = -2;   // a ray still to be followed
  static constexpr int kLeftOut = -3;   // a ray left out once the byte was settled: adds 0

  struct Level {
    Vec3<T> local;   // clamped
    Vec3<T> weight;  // the material's specular: how much of the reflection is added
    T keep = 1;      // 1 - transparency: how much of the local colour stays
    Vec3<T> filter{0};
    int reflected = kNone;    // the level of the reflected ray's hit, if traced
    int transmitted = kNone;  // the level of the transmitted ray's hit, if traced
    Vec3<T> value{0};
  };

  struct PendingRay {
    Vec3<T> origin, dir;
    Origin from;
    T travelled, path_weight;
    int depth;
    int parent = kNone;        // the level this ray leaves
    bool reflection = false;   // the parent's reflected ray; else its transmitted ray
    const Hit<T>* known = nullptr;  // its closest hit, where that is known already
  };

  // `first`, when given, is the closest hit of the first ray; `bounce`, when given, that of
  // the reflection ray its hit sends.
  Vec3<T> trace(Vec3<T> origin, Vec3<T> dir, const Hit<T>* first, const Hit<T>* bounce = nullptr) {
    levels_.clear();
    pending_.clear();
    settled_ = false;
    follow(origin, dir, Origin{}, 0, 1, 0, kNone, kNone, first, bounce);
    while (!pending_.empty()) {
      const PendingRay r = take_pending();
      if (!settled_ && heaviest_first()) {
        T weight = r.path_weight;  // of everything still to follow
        for (const PendingRay& q : pending_) weight += q.path_weight;
        settle_now(weight);
      }
      if (settled_) {
        (r.reflection ? levels_[r.parent].reflected : levels_[r.parent].transmitted) = kLeftOut;
        continue;
      }
      follow(r.origin, r.dir, r.from, r.travelled, r.path_weight, r.depth,
             r.reflection ? r.parent : kNone, r.reflection ? kNone : r.parent, r.known, nullptr);
    }
    // Children come after their parents: fold from the last level back (a ray left out
    // adds 0, as in byte_settled's lower bound).
    auto value = [&](int level) { return level >= 0 ? levels_[level].value : Vec3<T>(0); };
    for (size_t i = levels_.size(); i-- > 0;) {
      Level& l = levels_[i];
      Vec3<T> c = l.local;
      if (l.transmitted != kNone) c = l.keep * c + l.filter * value(l.transmitted);
      if (l.reflected != kNone) c = clamp01(c + l.weight * value(l.reflected));
      l.value = c;
    }
    if (recording()) record_levels();
    return levels_.front().value;
  }

  // Queues a ray to follow later: last in, first out, or (best_first_) in a heap by path
  // weight, while the path is short enough to settle; past that the order no longer helps,
  // and the rest go last in, first out.
  void queue(const PendingRay& r) {
    pending_.push_back(r);
    if (heaviest_first()) std::push_heap(pending_.begin(), pending_.end(), lighter);
  }

  // The next pending ray: the last queued, or (heaviest_first) one of the largest path weight.
  PendingRay take_pending() {
    if (heaviest_first()) std::pop_heap(pending_.begin(), pending_.end(), lighter);
    const PendingRay r = pending_.back();
    pending_.pop_back();
    return r;
  }

  bool heaviest_first() const { return best_first_ && levels_.size() <= kMaxSettledLevels; }

  static bool lighter(const PendingRay& a, const PendingRay& b) {
    return a.path_weight < b.path_weight;
  }

  // Follows one ray and, but in best-first order, its chain of reflections, adding a level
  // per hit; a translucent hit queues its transmitted ray. The ray is the reflection of level
  // `previous`, or the transmitted ray of level `parent`, or (neither) the first. `first`,
  // when given, is its closest hit; `bounce` that of the reflection ray its hit sends.
  // (Arguments one by one: a PendingRay built just before the call and read whole in it
  // stalled the loads on the stores, 1% of grid-8000's render.)
  void follow(Vec3<T> origin, Vec3<T> dir, Origin from, T travelled, T path_weight, int depth,
              int previous, int parent, const Hit<T>* first, const Hit<T>* bounce) {
    const bool secondary = previous >= 0 || parent >= 0;
    for (int step = 0;; ++step, ++depth) {
      const int index = static_cast<int>(levels_.size());
      if (previous >= 0)
        levels_[previous].reflected = index;
      else if (parent >= 0)
        levels_[parent].transmitted = index;
      if (step > 0 || secondary) ++counts.reflection;
      const Hit<T>* known = step == 0 ? first : step == 1 ? bounce : nullptr;
      Hit<T> hit = known ? *known : closest(origin, dir, from, s_.max_dist - travelled);
      if (hit.object < 0) {
        if (recording())
          record_ray(origin, dir, from, travelled, depth, previous, parent, hit, nullptr);
        levels_.push_back({s_.background, Vec3<T>(0)});
        return;
      }
      const T r_total = travelled + hit.t;
      const Vec3<T> p = origin + hit.t * dir;
      const Surface sf = surface(hit.object, p, dir);
      const PreparedMaterial<T>& m = *sf.m;
      if (recording()) record_ray(origin, dir, from, travelled, depth, previous, parent, hit, &sf);

      Vec3<T> colour = sf.ambient / r_total;
      if (s_.features.lights)
        add_direct_light(colour, p, sf, dir, {hit.object, sf.inside});
      colour = clamp01(colour);
      levels_.push_back({colour, Vec3<T>(0)});

      // Reflection and transmission together branch: a budget of levels per primary ray
      // keeps a hall of translucent mirrors from doubling its rays at every bounce.
      const bool budget = !s_.features.transparency || levels_.size() < kMaxBranchingLevels;
      if (s_.features.transparency && m.transparency > 0 && depth < s_.max_depth && budget) {
        levels_[index].keep = 1 - m.transparency;
        levels_[index].filter = m.filter;
        // Straight on through the surface: into the object it was outside of, and out again.
        levels_[index].transmitted = kPending;
        queue({p, dir, Origin{hit.object, !sf.inside}, r_total, path_weight * m.transparency,
               depth + 1, index});
      }
      if (!reflects(m, depth, path_weight, budget)) return;
      levels_[index].weight = m.specular;
      levels_[index].reflected = kPending;
      const Vec3<T> out = reflected(dir, sf.n);
      if (best_first_) {  // it waits its turn with the transmitted rays
        queue({p, out, {hit.object, sf.inside}, r_total, path_weight * m.max_specular,
               depth + 1, index, true, step == 0 ? bounce : nullptr});
        return;
      }
      if (settle_ && settle_now(path_weight * m.max_specular)) {
        levels_[index].reflected = kLeftOut;
        return;
      }
      path_weight *= m.max_specular;
      dir = out;
      origin = p;
      travelled = r_total;
      from = {hit.object, sf.inside};
      previous = index;
    }
  }

  // Whether the byte is settled now, with `weight` the sum of the path weights of the rays
  // still to follow. Only asked where the rays left could not move the colour by a whole
  // byte, and the bounds are not too long to fold.
  bool settle_now(T weight) {
    settled_ = weight < T(kSettleWeight) && levels_.size() <= kMaxSettledLevels &&
               byte_settled();
    return settled_;
  }

  // Whether the pixel's byte is the same whatever the rays still pending bring. Each adds a
  // value in [0, value_bound()] (any level's value: see there), and each step of the fold in
  // trace() is monotone in it: its weights (specular, keep, filter) are finite and not
  // negative (Features::byte_cutoff), clamping is monotone, and so is every rounding. So the
  // fold with all of them at 0 and with all of them at the bound brackets the colour the
  // whole path would give, and the colour with the pending rays left out (at 0); where the
  // two ends make one byte, so do those.
  bool byte_settled() {
    bounds_.resize(levels_.size());
    const T top = value_bound();
    auto low = [&](int level) { return level >= 0 ? bounds_[level][0] : Vec3<T>(0); };
    auto high = [&](int level) {
      return level >= 0 ? bounds_[level][1] : level == kPending ? Vec3<T>(top) : Vec3<T>(0);
    };
    for (size_t i = levels_.size(); i-- > 0;) {
      const Level& l = levels_[i];
      Vec3<T> lo = l.local, hi = l.local;
      if (l.transmitted != kNone) {
        lo = l.keep * lo + l.filter * low(l.transmitted);
        hi = l.keep * hi + l.filter * high(l.transmitted);
      }
      if (l.reflected != kNone) {
        lo = clamp01(lo + l.weight * low(l.reflected));
        hi = clamp01(hi + l.weight * high(l.reflected));
      }
      bounds_[i] = {lo, hi};
    }
    const Vec3<T>& lo = bounds_.front()[0];
    const Vec3<T>& hi = bounds_.front()[1];
    for (int c = 0; c < 3; ++c)
      if (film_.to_byte(static_cast<double>(lo[c])) != film_.to_byte(static_cast<double>(hi[c])))
        return false;
    return true;
  }

  // No level's value exceeds this. A level that reflects is clamped to [0, 1], and so are a
  // local colour and the background; one that only lets light through is keep·local +
  // filter·value, which stays under 1 + 2^-10 while no transparency lies within 2^-8 of 1
  // without being 1 (Features::byte_cutoff): filter is at most transparency (checked, to
  // 2^-20 of it) and keep is 1 - transparency to a rounding, and their margin below the
  // bound, about 2^-8 · 2^-10, is far above those errors even in float. At transparency 1,
  // keep is 0 and filter at most 1.
  T value_bound() const { return s_.features.transparency ? T(1) + T(1) / 1024 : T(1); }

  // Whether a hit on material m sends a reflection ray (follow() and primary_bounce()).
  bool reflects(const PreparedMaterial<T>& m, int depth, T path_weight, bool budget) const {
    return s_.features.reflection && m.reflects && depth < s_.max_depth && budget &&
           !(path_weight * m.max_specular < s_.bailout);
  }

  static Vec3<T> reflected(const Vec3<T>& dir, const Vec3<T>& n) {
    return dir - (2 * glm::dot(n, dir)) * n;
  }

  // Adds each light's term in scene order, as the formula reads.
  void add_direct_light(Vec3<T>& colour, const Vec3<T>& p, const Surface& sf, const Vec3<T>& dir,
                        Origin from) {
    const PreparedMaterial<T>& m = *sf.m;
    const Vec3<T>& n = sf.n;
    const Vec3<T> v = -dir;
    const T point_scale = largest_coordinate(p);
    if (blockers_.size() != s_.lights.size()) blockers_.assign(s_.lights.size(), -1);
    const bool remember = !s_.bvh.empty() || !s_.shape_bvh.empty();  // small scenes: just loop
    for (std::size_t i = 0; i < s_.lights.size(); ++i) {
      const PreparedLight<T>& light = s_.lights[i];
      RecordedLight* lr = recording()
                              ? &rec_->light(static_cast<int>(levels_.size()), static_cast<int>(i))
                              : nullptr;
      int* last_blocker = remember ? &blockers_[i] : nullptr;
      const LightBuffer* light_buffer =
          i < s_.light_buffers.size() && !s_.light_buffers[i].empty() ? &s_.light_buffers[i]
                                                                       : nullptr;
      Vec3<T> l = light.location - p;
      T r = glm::length(l);
      // A light exactly at the shaded point has no direction: it contributes nothing.
      if (!(r > 0) || !std::isfinite(r)) {
        if (lr) lr->status = RecordedLight::at_point;
        continue;
      }
      l /= r;
      T n_dot_l = glm::dot(n, l);
      // Near 0 the sign of N.L is the rounding noise of L = Lp - p (a light in the surface's
      // own plane): it would switch the light and its highlight on and off pixel by pixel.
      const T noise = 8 * std::numeric_limits<T>::epsilon() * (light.scale + point_scale) / r;
      if (lr) {
        lr->distance = static_cast<double>(r);
        lr->n_dot_l = static_cast<double>(n_dot_l);
      }
      if (!(n_dot_l > noise)) {
        if (lr) lr->status = RecordedLight::faces_away;
        continue;
      }
      Vec3<T> e = light.emissivity / r;
      if (light.kind != LightKind::point && !reaches(light, l, e)) {
        if (lr)
          lr->status = light.kind == LightKind::spot ? RecordedLight::outside_cone
                                                     : RecordedLight::off_slide;
        continue;
      }
      // A material lights cannot change gets exact zeros, unless E/r overflowed (then the
      // NaN it makes must appear exactly as in the general path).
      if (!m.lit && std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z)) {
        if (lr) record_unlit(*lr, p, l, from, r - 4 * noise * r, e);
        continue;
      }
      if (s_.features.shadows) {
        ++counts.shadow;
        // A surface through the light itself (a light placed on an object) is not in the
        // way: hits within the rounding noise of the light's position do not block.
        const T reach = r - 4 * noise * r;
        if (s_.features.transparency) {
          const Vec3<T> through = transmittance(p, l, from, reach);
          if (lr) record_shadow(*lr, p, l, from, reach, through == Vec3<T>(0));
          if (through == Vec3<T>(0)) continue;
          e *= through;
        } else if (occluded(p, l, from, reach, last_blocker, light_buffer)) {
          if (lr) record_shadow(*lr, p, l, from, reach, true);
          continue;
        }
      }
      Vec3<T> term = sf.diffuse * n_dot_l;
      if (lr) {
        lr->emissivity = triple(e);
        lr->diffuse = triple(e * term);
      }
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
        const T b = base > 0 ? base : T(0);
        if (!highlight_negligible(m, b, term)) term += m.specular * std::pow(b, m.shininess);
        if (lr) {
          lr->highlight_base = static_cast<double>(b);  // what is raised, as recorder.h says
          lr->specular = triple(e * (m.specular * std::pow(b, m.shininess)));
        }
      }
      colour += e * term;
    }
  }

  // The recorder's entry for the ray just followed, whose hit (`sf` null: a miss) becomes
  // level levels_.size().
  void record_ray(const Vec3<T>& origin, const Vec3<T>& dir, Origin from, T travelled, int depth,
                  int previous, int parent, const Hit<T>& hit, const Surface* sf) {
    const RecordedHit::Ray ray = previous >= 0 ? RecordedHit::Ray::reflected
                                 : parent >= 0 ? RecordedHit::Ray::transmitted
                                               : RecordedHit::Ray::primary;
    RecordedHit& rh = rec_->hits[rec_->begin(ray, previous >= 0 ? previous : parent, depth)];
    rh.origin = triple(origin);
    rh.direction = triple(dir);
    rh.travelled = static_cast<double>(travelled);
    if (!sf) {
      // Only a finite max_dist can hide an object.
      constexpr T kFar = std::numeric_limits<T>::max();
      rh.capped = s_.max_dist < kFar && closest(origin, dir, from, kFar).object >= 0;
      return;
    }
    rh.object = hit.object;
    rh.t = static_cast<double>(hit.t);
    rh.travelled = static_cast<double>(travelled + hit.t);
    rh.point = triple(origin + hit.t * dir);
    rh.normal = triple(sf->n);
    rh.ambient = triple(sf->ambient);
    rh.diffuse_colour = triple(sf->diffuse);
    rh.specular = triple(sf->m->specular);
    rh.shininess = static_cast<double>(sf->m->shininess);
  }

  // What the shadow ray to a light met: `blocked`, or else filtered by what it crossed.
  void record_shadow(RecordedLight& lr, const Vec3<T>& p, const Vec3<T>& l, Origin from, T reach,
                     bool blocked) const {
    if (!rec_->blockers && !s_.features.transparency) {  // then nothing filters
      lr.status = blocked ? RecordedLight::shadowed : RecordedLight::lit;
      return;
    }
    lr.blocker = shadow_blocker(p, l, from, reach);
    lr.status = blocked           ? RecordedLight::shadowed
                : lr.blocker >= 0 ? RecordedLight::filtered
                                  : RecordedLight::lit;
  }

  // The first opaque object a shadow ray meets before `dist` or, when there is none, the
  // first translucent one; -1 when it meets nothing. Walks as transmittance() does.
  int shadow_blocker(Vec3<T> o, const Vec3<T>& d, Origin from, T dist) const {
    int first_filter = -1;
    for (int steps = 0; steps < 4 * kMaxCrossings; ++steps) {
      const Hit<T> hit = closest(o, d, from, dist);
      if (hit.object < 0 || !(hit.t < dist)) break;
      if (!(s_.materials[material_of(hit.object)].transparency > 0)) return hit.object;
      if (first_filter < 0) first_filter = hit.object;
      const Vec3<T> p = o + hit.t * d;
      from = {hit.object, glm::dot(outward_normal(hit.object, p), d) < 0};
      o = p;
      dist -= hit.t;
    }
    return first_filter;
  }

  // A light on a material it cannot change, whose shadow ray the tracer skips: for the
  // record, whether that ray would have reached the point.
  void record_unlit(RecordedLight& lr, const Vec3<T>& p, const Vec3<T>& l, Origin from, T reach,
                    const Vec3<T>& e) const {
    lr.emissivity = triple(e);
    if (!s_.features.shadows) return;
    const Vec3<T> through = s_.features.transparency
                                ? transmittance(p, l, from, reach)
                                : Vec3<T>(closest(p, l, from, reach).t < reach ? 0 : 1);
    record_shadow(lr, p, l, from, reach, through == Vec3<T>(0));
    lr.emissivity = triple(e * through);
  }

  // The levels' colours, once folded, into the recorder (its hits are the levels).
  void record_levels() {
    for (std::size_t i = 0; i < levels_.size(); ++i) {
      RecordedHit& rh = rec_->hits[i];
      const Level& l = levels_[i];
      rh.local = triple(l.local);
      rh.value = triple(l.value);
      rh.weight = triple(l.weight);
      rh.keep = static_cast<double>(l.keep);
      rh.filter = triple(l.filter);
      rh.reflected = l.reflected;
      rh.transmitted = l.transmitted;
    }
  }

  // Spotlights and projectors: whether the light leaves towards the point (-l) at all, and
  // through which colour of a projector's slide.
  static bool reaches(const PreparedLight<T>& light, const Vec3<T>& l, Vec3<T>& e) {
    if (light.kind == LightKind::spot) return glm::dot(-l, light.direction) > light.cos_theta;
    const PreparedShape<T>& slide = light.slide;
    const auto t = plane_distance(light.location, -l, slide.normal, slide.point);
    if (!t || !(*t > 0)) return false;
    const Vec3<T> q = light.location - *t * l;
    T qx, qy;
    frame_coords(slide, q, qx, qy);
    if (!(qx >= 0 && qx <= slide.width && qy >= 0 && qy <= slide.height)) return false;
    e *= shape_texel(slide, q);
    return true;
  }

  // The bounds are folded afresh each time they are asked: past this many levels (a chain
  // deeper than 63 bounces, or a translucent scene's tree) the path is followed to its end.
  static constexpr std::size_t kMaxSettledLevels = 64;
  // They are asked only once the rays left weigh less than a byte in all: above that, only a
  // saturated colour could settle the byte (none did in the benchmark scenes).
  static constexpr double kSettleWeight = 1.0 / 255;

  const PreparedScene<T>& s_;
  bool settle_ = false;   // stop_at_settled_bytes
  bool settled_ = false;  // this path's byte is settled: nothing more is followed
  bool best_first_ = false;  // the pending rays are taken heaviest first
  Film film_;
  std::vector<std::array<Vec3<T>, 2>> bounds_;  // byte_settled's, per level
  std::vector<Level> levels_;
  std::vector<PendingRay> pending_;
  std::vector<int> blockers_;  // per light: the object that blocked its last shadow ray
  Recorder* rec_ = nullptr;    // only with kRecord
};

}  // namespace rayfarm
