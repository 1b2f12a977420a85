// A bounding volume hierarchy over boxes (the scene's spheres): built as a binary tree by
// binned SAH, then collapsed to four children per node (eight on processors with AVX2) and
// flattened into an array, so one 4-wide (8-wide) float comparison per slab tests all
// children of a node. Traversal visits leaves nearest first (closest hit) or until one
// reports a hit (shadow rays); what a hit means is the caller's business.
//
// The box test must never miss a primitive the caller's own test would hit, or the image
// would change. Boxes are rounded outward to float and every slab is widened by a margin
// that covers the rounding of both the slab test and the caller's intersection routine
// (see BvhRay), so the hierarchy only ever skips what is truly out of reach.
#pragma once

#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <glm/vec3.hpp>
#include <initializer_list>
#include <limits>
#include <span>
#include <vector>

namespace rayfarm {

struct BvhBox {
  glm::dvec3 lo;
  glm::dvec3 hi;
};

// W children side by side, each box as lo x y z, hi x y z across the W lanes.
// A slot is an inner node (count 0, child = node index), a leaf (count > 0, child = first
// primitive in `order`) or empty (count -1, an inverted box no ray meets).
template <int W>
struct alignas(64) BvhNodeOf {
  float box[6][W];
  std::int32_t child[W];
  std::int32_t count[W];
};
using BvhNode = BvhNodeOf<4>;   // one SSE comparison per axis: any x86-64
using BvhNode8 = BvhNodeOf<8>;  // one AVX comparison per axis: for processors with AVX2
static_assert(sizeof(BvhNode) == 128);
static_assert(sizeof(BvhNode8) == 256);

struct BvhStats {
  int nodes = 0;
  int leaves = 0;
  int depth = 0;  // of the binary tree before collapsing
  double mean_leaf = 0;
};

// The tree is stored 4-wide (`nodes`) or 8-wide (`nodes8`), never both; [0] is the root.
// Both are the same binary tree collapsed, so they list the same leaves.
struct Bvh {
  std::vector<BvhNode> nodes;
  std::vector<BvhNode8> nodes8;
  std::vector<std::int32_t> order;  // primitive indices in leaf order
  double scale = 0;                 // largest coordinate magnitude of any box
  BvhStats stats;

  // (One load: `order` is filled exactly when one of the node arrays is.)
  bool empty() const { return order.empty(); }
};

struct BvhBuildOptions {
  int threads = 1;   // the result does not depend on it
  int max_leaf = 4;  // a larger set is always split when it can be
  int width = 4;     // 4, or 8 where bvh_best_width() says so
  // Collapsing, a subtree of at most merge_max primitives, all numbered below merge_below
  // (those cheap to test: spheres), becomes one leaf in its parent's slot instead of a
  // node of its own (1: every leaf as the binary tree has it) where the surface area
  // heuristic says it pays, a node visit costing merge_node_cost primitive tests.
  int merge_max = 1;
  std::size_t merge_below = std::numeric_limits<std::size_t>::max();
  float merge_node_cost = 4;
};

// 8 on a processor with AVX2, whose 8-wide walks below visit fewer levels; else 4. The
// walks' answers do not depend on the width: the hit is chosen by (t, index), whatever the
// order in which leaves are met.
int bvh_best_width();

// The smallest box around some points.
inline BvhBox box_around(std::initializer_list<glm::dvec3> points) {
  BvhBox b{glm::dvec3(std::numeric_limits<double>::infinity()),
           glm::dvec3(-std::numeric_limits<double>::infinity())};
  for (const glm::dvec3& q : points)
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = std::min(b.lo[a], q[a]);
      b.hi[a] = std::max(b.hi[a], q[a]);
    }
  return b;
}

// Builds the hierarchy; empty when there are no boxes or their coordinates do not fit the
// float nodes comfortably (the caller then keeps its plain loop).
Bvh build_bvh(std::span<const BvhBox> boxes, const BvhBuildOptions& options = {});
// The same over `count` boxes given one by one (no array of them: for 100,000 spheres, 4.8 MB
// less fresh memory).
Bvh build_bvh(std::size_t count, const std::function<BvhBox(std::size_t)>& box_of,
              const BvhBuildOptions& options = {});

// The binary tree is at most this deep (the builder turns to median splits well before), so
// the traversal stacks below cannot overflow: at most 3 entries are pushed per level.
inline constexpr int kBvhMaxDepth = 64;

namespace bvh_simd {
using F4 = float __attribute__((vector_size(16)));
using I4 = std::int32_t __attribute__((vector_size(16)));

inline F4 load(const float* p) {
  F4 v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
inline F4 splat(float x) { return F4{x, x, x, x}; }
inline F4 vmin(F4 a, F4 b) { return a < b ? a : b; }
inline F4 vmax(F4 a, F4 b) { return a > b ? a : b; }
inline int bits(I4 m) {
#if defined(__SSE__)
  return __builtin_ia32_movmskps(reinterpret_cast<F4>(m));
#else
  return (m[0] & 1) | (m[1] & 2) | (m[2] & 4) | (m[3] & 8);
#endif
}
}  // namespace bvh_simd

// A ray set up for slab tests against the float nodes. Each slab is moved out by `margin`
// (near planes towards the ray, far planes away), folded into two shifted origins.
struct BvhRay {
  bvh_simd::F4 near_origin[3];  // each value in all four lanes
  bvh_simd::F4 far_origin[3];
  bvh_simd::F4 inv_dir[3];
  int near_row[3];  // row of box[] holding the near plane of each axis: a, or 3 + a
  int far_row[3];

  // Sets the ray up; false when the origin is too far out for float nodes (the caller then
  // uses its loop). Not a constructor: an uninitialised BvhRay costs nothing.
  template <class V>
  bool init(const V& origin, const V& dir, double scene_scale) {
    using bvh_simd::splat;
    const double o[3] = {static_cast<double>(origin.x), static_cast<double>(origin.y),
                         static_cast<double>(origin.z)};
    const double extent = std::max({std::abs(o[0]), std::abs(o[1]), std::abs(o[2])}) + scene_scale;
    if (!(extent < 1e18)) return false;
    // A hit computed by the caller's sphere test (in float, at worst) lies within a few tens
    // of float epsilons of (|origin| + scene scale) from the true surface, and the slab test
    // adds a few more. The margin is 128 epsilons of that; the grazing rays of
    // tests/bvh_test.cpp need a fraction of one.
    const double margin = extent * 0x1p-16;
    const double d[3] = {static_cast<double>(dir.x), static_cast<double>(dir.y),
                         static_cast<double>(dir.z)};
    for (int a = 0; a < 3; ++a) {
      // A zero (or tiny) component becomes tiny but finite, so no 0 * inf NaN can appear;
      // slab distances then come out huge, as they are for a parallel ray.
      float df = static_cast<float>(d[a]);
      if (!(std::abs(df) >= 1e-30f)) df = std::copysign(1e-30f, static_cast<float>(d[a]));
      const float inv = 1.0f / df;
      const bool neg = inv < 0;
      inv_dir[a] = splat(inv);
      near_row[a] = neg ? 3 + a : a;
      far_row[a] = neg ? a : 3 + a;
      near_origin[a] = splat(static_cast<float>(neg ? o[a] - margin : o[a] + margin));
      far_origin[a] = splat(static_cast<float>(neg ? o[a] + margin : o[a] - margin));
    }
    return true;
  }

  // Bit i set: the ray meets child i's widened box within [0, limit]; t_near its entries.
  [[gnu::always_inline]] int hits(const BvhNode& n, float limit, bvh_simd::F4& t_near) const {
    using namespace bvh_simd;
    F4 tn = (load(n.box[near_row[0]]) - near_origin[0]) * inv_dir[0];
    F4 tf = (load(n.box[far_row[0]]) - far_origin[0]) * inv_dir[0];
    tn = vmax(tn, (load(n.box[near_row[1]]) - near_origin[1]) * inv_dir[1]);
    tf = vmin(tf, (load(n.box[far_row[1]]) - far_origin[1]) * inv_dir[1]);
    tn = vmax(tn, (load(n.box[near_row[2]]) - near_origin[2]) * inv_dir[2]);
    tf = vmin(tf, (load(n.box[far_row[2]]) - far_origin[2]) * inv_dir[2]);
    t_near = tn;
    return bits((tn <= tf) & (tf >= splat(0.0f)) & (tn <= splat(limit)));
  }
};

// A float limit no smaller than `t` (so rounding can never cut a hit off).
template <class T>
inline float float_limit_up(T t) {
  constexpr T kMax = static_cast<T>(std::numeric_limits<float>::max());
  if (t > kMax) return std::numeric_limits<float>::infinity();
  float f = static_cast<float>(t);
  if (static_cast<T>(f) < t) {
    // The next float up, without a library call (this runs for every ray): f is finite here.
    if (f == 0) return std::numeric_limits<float>::denorm_min();
    std::uint32_t bits = __builtin_bit_cast(std::uint32_t, f);
    bits += f > 0 ? 1 : -1;
    f = __builtin_bit_cast(float, bits);
  }
  return f;
}

namespace bvh_detail {
struct Entry {
  std::int32_t child;
  std::int32_t count;  // 0: an inner node
  float t_near;
};

// Both cache lines of an inner node a traversal is about to visit.
inline void prefetch(const BvhNode* nodes, std::int32_t child, std::int32_t count) {
  if (count == 0) {
    const char* p = reinterpret_cast<const char*>(nodes + child);
    __builtin_prefetch(p);
    __builtin_prefetch(p + 64);
  }
}

inline int pop_bit(int& mask) {
  const int i = __builtin_ctz(static_cast<unsigned>(mask));
  mask &= mask - 1;
  return i;
}

// The walks over 4-wide nodes.
template <class Leaf>
void closest4(const Bvh& bvh, const BvhRay& ray, float limit, Leaf& leaf) {
  Entry stack[3 * kBvhMaxDepth + 4];
  int top = 0;
  const BvhNode* nodes = bvh.nodes.data();
  Entry cur{0, 0, 0};
  for (;;) {
    if (cur.count > 0) {
      limit = leaf(cur.child, cur.count);
    } else {
      const BvhNode& n = nodes[cur.child];
      bvh_simd::F4 t;
      int mask = ray.hits(n, limit, t);
      if (mask) {
        // One child: go on. Two: the nearer now, the other later. More: sort them.
        const int i = pop_bit(mask);
        prefetch(nodes, n.child[i], n.count[i]);
        if (!mask) {
          cur = {n.child[i], n.count[i], t[i]};
          continue;
        }
        const int j = pop_bit(mask);
        prefetch(nodes, n.child[j], n.count[j]);
        Entry a{n.child[i], n.count[i], t[i]}, b{n.child[j], n.count[j], t[j]};
        if (b.t_near < a.t_near) std::swap(a, b);
        if (!mask) {
          stack[top++] = b;
          cur = a;
          continue;
        }
        Entry e[4] = {b, a};  // farthest first
        int k = 2;
        while (mask) {
          const int c = pop_bit(mask);
          prefetch(nodes, n.child[c], n.count[c]);
          Entry x{n.child[c], n.count[c], t[c]};
          int m = k++;
          for (; m > 0 && e[m - 1].t_near < x.t_near; --m) e[m] = e[m - 1];
          e[m] = x;
        }
        // All three copied whatever k is: a fixed copy, not a loop the compiler turns into
        // a slow string move; the unused slot is overwritten by the next push.
        stack[top] = e[0];
        stack[top + 1] = e[1];
        stack[top + 2] = e[2];
        top += k - 1;
        cur = e[k - 1];
        continue;
      }
    }
    for (;;) {
      if (top == 0) return;
      cur = stack[--top];
      if (cur.t_near <= limit) break;
    }
  }
}

template <class Leaf>
bool any4(const Bvh& bvh, const BvhRay& ray, float limit, Leaf& leaf) {
  struct Slot {
    std::int32_t child, count;
  };
  Slot stack[3 * kBvhMaxDepth + 4];
  int top = 0;
  const BvhNode* nodes = bvh.nodes.data();
  Slot cur{0, 0};
  for (;;) {
    if (cur.count > 0) {
      if (leaf(cur.child, cur.count)) return true;
    } else {
      const BvhNode& n = nodes[cur.child];
      bvh_simd::F4 t;
      int mask = ray.hits(n, limit, t);
      if (mask) {
        int i = pop_bit(mask);
        while (mask) {
          prefetch(nodes, n.child[i], n.count[i]);
          stack[top++] = {n.child[i], n.count[i]};
          i = pop_bit(mask);
        }
        prefetch(nodes, n.child[i], n.count[i]);
        cur = {n.child[i], n.count[i]};
        continue;
      }
    }
    if (top == 0) return false;
    cur = stack[--top];
  }
}

// The same walks over 8-wide nodes, compiled for AVX2 (called only where bvh_best_width()
// chose them). The leaf callback is inlined into them and so compiled for AVX2 too: the
// same IEEE operations (fused multiply-adds are not enabled), so the same answers.
struct Ray8 {
  __m256 near_origin[3], far_origin[3], inv_dir[3];
};

[[gnu::target("avx2"), gnu::always_inline]] inline Ray8 ray8(const BvhRay& r) {
  Ray8 w;
  for (int a = 0; a < 3; ++a) {
    w.near_origin[a] = _mm256_set1_ps(r.near_origin[a][0]);
    w.far_origin[a] = _mm256_set1_ps(r.far_origin[a][0]);
    w.inv_dir[a] = _mm256_set1_ps(r.inv_dir[a][0]);
  }
  return w;
}

[[gnu::target("avx2"), gnu::always_inline]] inline __m256 slab8(const float* row, __m256 origin,
                                                                __m256 inv_dir) {
  return _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(row), origin), inv_dir);
}

// BvhRay::hits for eight children: the same operations in the same order (max and min
// return the second operand on an unordered pair, as vmax and vmin do).
[[gnu::target("avx2"), gnu::always_inline]] inline int hits8(const BvhNode8& n, const BvhRay& r,
                                                             const Ray8& w, float limit,
                                                             float (&t_near)[8]) {
  // (No lambda for the slab: a lambda would not be compiled for AVX2.)
  __m256 tn = slab8(n.box[r.near_row[0]], w.near_origin[0], w.inv_dir[0]);
  __m256 tf = slab8(n.box[r.far_row[0]], w.far_origin[0], w.inv_dir[0]);
  tn = _mm256_max_ps(tn, slab8(n.box[r.near_row[1]], w.near_origin[1], w.inv_dir[1]));
  tf = _mm256_min_ps(tf, slab8(n.box[r.far_row[1]], w.far_origin[1], w.inv_dir[1]));
  tn = _mm256_max_ps(tn, slab8(n.box[r.near_row[2]], w.near_origin[2], w.inv_dir[2]));
  tf = _mm256_min_ps(tf, slab8(n.box[r.far_row[2]], w.far_origin[2], w.inv_dir[2]));
  _mm256_store_ps(t_near, tn);
  const __m256 in = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(tn, tf, _CMP_LE_OQ),
                                                _mm256_cmp_ps(tf, _mm256_setzero_ps(), _CMP_GE_OQ)),
                                  _mm256_cmp_ps(tn, _mm256_set1_ps(limit), _CMP_LE_OQ));
  return _mm256_movemask_ps(in);
}

// All four cache lines of an 8-wide inner node a walk is about to visit.
inline void prefetch8(const BvhNode8* nodes, std::int32_t child, std::int32_t count) {
  if (count == 0) {
    const char* p = reinterpret_cast<const char*>(nodes + child);
    __builtin_prefetch(p);
    __builtin_prefetch(p + 64);
    __builtin_prefetch(p + 128);
    __builtin_prefetch(p + 192);
  }
}

// At most 7 entries are pushed per level.
// (closest8 copies seven entries from the top whatever it pushes: within the same bound.)
inline constexpr int kStack8 = 7 * kBvhMaxDepth + 8;

template <class Leaf>
[[gnu::target("avx2")]] void closest8(const Bvh& bvh, const BvhRay& ray, float limit, Leaf& leaf) {
  const Ray8 w = ray8(ray);
  Entry stack[kStack8];
  int top = 0;
  const BvhNode8* nodes = bvh.nodes8.data();
  Entry cur{0, 0, 0};
  for (;;) {
    if (cur.count > 0) {
      limit = leaf(cur.child, cur.count);
    } else {
      const BvhNode8& n = nodes[cur.child];
      alignas(32) float t[8];
      int mask = hits8(n, ray, w, limit, t);
      if (mask) {
        // One child: go on. Two: the nearer now, the other later. More: sort them.
        const int i = pop_bit(mask);
        prefetch8(nodes, n.child[i], n.count[i]);
        if (!mask) {
          cur = {n.child[i], n.count[i], t[i]};
          continue;
        }
        const int j = pop_bit(mask);
        prefetch8(nodes, n.child[j], n.count[j]);
        Entry a{n.child[i], n.count[i], t[i]}, b{n.child[j], n.count[j], t[j]};
        if (b.t_near < a.t_near) std::swap(a, b);
        if (!mask) {
          stack[top++] = b;
          cur = a;
          continue;
        }
        Entry e[8] = {b, a};  // farthest first
        int k = 2;
        while (mask) {
          const int c = pop_bit(mask);
          prefetch8(nodes, n.child[c], n.count[c]);
          Entry x{n.child[c], n.count[c], t[c]};
          int m = k++;
          for (; m > 0 && e[m - 1].t_near < x.t_near; --m) e[m] = e[m - 1];
          e[m] = x;
        }
        // All seven copied whatever k is (e's unused slots are zero): a fixed copy, not a
        // loop the compiler turns into a slow string move; the unused slots are overwritten
        // by the next pushes.
        __builtin_memcpy(stack + top, e, 7 * sizeof(Entry));
        top += k - 1;
        cur = e[k - 1];
        continue;
      }
    }
    for (;;) {
      if (top == 0) return;
      cur = stack[--top];
      if (cur.t_near <= limit) break;
    }
  }
}

template <class Leaf>
[[gnu::target("avx2")]] bool any8(const Bvh& bvh, const BvhRay& ray, float limit, Leaf& leaf) {
  struct Slot {
    std::int32_t child, count;
  };
  const Ray8 w = ray8(ray);
  Slot stack[kStack8];
  int top = 0;
  const BvhNode8* nodes = bvh.nodes8.data();
  Slot cur{0, 0};
  for (;;) {
    if (cur.count > 0) {
      if (leaf(cur.child, cur.count)) return true;
    } else {
      const BvhNode8& n = nodes[cur.child];
      alignas(32) float t[8];
      int mask = hits8(n, ray, w, limit, t);
      if (mask) {
        int i = pop_bit(mask);
        while (mask) {
          prefetch8(nodes, n.child[i], n.count[i]);
          stack[top++] = {n.child[i], n.count[i]};
          i = pop_bit(mask);
        }
        prefetch8(nodes, n.child[i], n.count[i]);
        cur = {n.child[i], n.count[i]};
        continue;
      }
    }
    if (top == 0) return false;
    cur = stack[--top];
  }
}
}  // namespace bvh_detail

// Visits leaves nearest first. `leaf(first, count)` tests order[first .. first + count) and
// returns the new limit (a float no smaller than the closest hit's t so far). A node whose
// entry lies beyond the limit is skipped; one entered exactly at the limit is not, so a
// tie can still be resolved by the caller.
template <class Leaf>
void bvh_closest(const Bvh& bvh, const BvhRay& ray, float limit, Leaf&& leaf) {
  if (!bvh.nodes8.empty())
    bvh_detail::closest8(bvh, ray, limit, leaf);
  else
    bvh_detail::closest4(bvh, ray, limit, leaf);
}

// Visits leaves until `leaf(first, count)` returns true (a hit); returns whether it did.
template <class Leaf>
bool bvh_any(const Bvh& bvh, const BvhRay& ray, float limit, Leaf&& leaf) {
  return !bvh.nodes8.empty() ? bvh_detail::any8(bvh, ray, limit, leaf)
                             : bvh_detail::any4(bvh, ray, limit, leaf);
}

}  // namespace rayfarm
