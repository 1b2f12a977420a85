// Binned SAH construction (Wald, "On fast Construction of SAH-based Bounding Volume
// Hierarchies", 2007) with 16 bins over the centroid bounds, all three axes binned in one
// pass; the top levels are built on separate threads into their own arrays and spliced in
// depth-first order, so the tree is the same for any thread count. The binary tree is then
// collapsed to four or eight children per node (each node adopts the grandchildren of its
// largest inner children) and flattened.
#include "accel/bvh.h"

#include <array>
#include <bit>
#include <cstdint>
#include <thread>

namespace rayfarm {
namespace {

constexpr int kBins = 16;                   // at most; small sets use one per primitive
constexpr int kMedianDepth = 32;            // below this, median splits: depth <= 32 + log2(n) < 64
constexpr std::size_t kParallelMin = 8192;  // smaller subtrees are not worth a thread
constexpr double kMaxCoordinate = 1e18;     // beyond this the float nodes get coarse
constexpr float kInf = std::numeric_limits<float>::infinity();

using bvh_simd::F4;
using bvh_simd::I4;
using bvh_simd::vmax;
using bvh_simd::vmin;

// Surface area of the box [lo, hi] (x, y, z at [0], [1], [2]); 0 if empty. One function for
// the build's boxes and the tree's nodes, so the collapse sees the areas the build did.
template <class V>
float box_area(const V& lo, const V& hi) {
  if (!(hi[0] >= lo[0])) return 0;
  const float e0 = hi[0] - lo[0], e1 = hi[1] - lo[1], e2 = hi[2] - lo[2];
  return 2 * (e0 * e1 + e1 * e2 + e2 * e0);
}

// A box as two 4-wide vectors (x, y, z, and a lane nobody reads).
struct Box3 {
  F4 lo = bvh_simd::splat(kInf);
  F4 hi = bvh_simd::splat(-kInf);

  void grow(const Box3& b) {
    lo = vmin(lo, b.lo);
    hi = vmax(hi, b.hi);
  }
  void grow(F4 p) {
    lo = vmin(lo, p);
    hi = vmax(hi, p);
  }
  void grow(F4 p_lo, F4 p_hi) {
    lo = vmin(lo, p_lo);
    hi = vmax(hi, p_hi);
  }
  float area() const { return box_area(lo, hi); }
};

// A primitive during the build: its box rounded outward to float (fourth lanes zero, so no
// arithmetic ever meets a stray denormal), and its index.
struct Ref {
  Box3 box;
  std::int32_t index;
  F4 centre2() const { return box.lo + box.hi; }  // twice the centre: no multiply needed
};

// A set's box and the box of its (doubled) centres.
struct Bounds {
  Box3 box;
  Box3 centres;
};

// A set's bins on each axis. A bin keeps the bounds of its boxes and of their centres: the
// children's bounds are then unions of bins, with no pass over the children to find them.
struct Bin {  // no initialisers: only the bins in use are cleared
  Box3 box;
  Box3 centres;
  std::int32_t count;
};
using Bins = std::array<std::array<Bin, kBins>, 3>;

// The binary tree, children side by side: inner nodes point at the first of two.
struct BuildNode {
  // The box as plain floats: 32 bytes a node where a Box3 made it 48 (some 100,000 nodes
  // for 60,000 spheres, all new memory).
  float lo[3], hi[3];
  std::int32_t index;  // inner: first child; leaf: first primitive
  std::int32_t count;  // 0 for an inner node

  void set_box(const Box3& b) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = b.lo[a];
      hi[a] = b.hi[a];
    }
  }
  float area() const { return box_area(lo, hi); }
};

// std::nextafter(f, -inf) and (f, +inf) for an f that is not NaN, and not the infinity it
// steps away from, without a library call: six per primitive were a tenth of the build.
float next_down(float f) {
  if (f == 0) return -std::numeric_limits<float>::denorm_min();
  const auto bits = std::bit_cast<std::uint32_t>(f);
  return std::bit_cast<float>(f > 0 ? bits - 1 : bits + 1);
}

float next_up(float f) { return -next_down(-f); }

float round_down(double v) {
  float f = static_cast<float>(v);
  return static_cast<double>(f) > v ? next_down(f) : f;
}

float round_up(double v) {
  float f = static_cast<float>(v);
  return static_cast<double>(f) < v ? next_up(f) : f;
}

// The bin of a (doubled) centre on each axis. NaN (0 * inf) lands in bin 0.
I4 bins_of(F4 centre2, F4 lo, F4 scale, float last) {
  const F4 f = vmin(vmax((centre2 - lo) * scale, bvh_simd::splat(0.0f)), bvh_simd::splat(last));
  return __builtin_convertvector(f, I4);
}

class Builder {
 public:
  Builder(std::vector<Ref>& refs, int max_leaf)
      : refs_(refs), scratch_(refs.size()), max_leaf_(max_leaf) {}

  // Fills nodes[slot] with the subtree over refs[begin, end), whose bounds are b; its
  // descendants are appended depth first (a child pair, then the first child's subtree,
  // then the second's). Returns the subtree's depth. `moved`: the range is in the scratch
  // array, where the last partition put it (partitions go back and forth between the two).
  // `bins`: this thread's, for every set it splits. (As a local of split(), 4 KB at each
  // level of the recursion, the bins of nested calls lay spread over the stack: the build
  // 23.0 -> 21.4 ms for shallow-60k's spheres.)
  int build(std::vector<BuildNode>& nodes, std::size_t slot, std::size_t begin, std::size_t end,
            const Bounds& b, int depth, int threads, Bins& bins, bool moved = false) {
    nodes[slot].set_box(b.box);
    Bounds left, right;
    const std::size_t mid = split(begin, end, b, depth, bins, left, right, moved);
    if (mid == begin) {
      if (moved) std::copy(scratch_.begin() + begin, scratch_.begin() + end, refs_.begin() + begin);
      nodes[slot].index = static_cast<std::int32_t>(begin);
      nodes[slot].count = static_cast<std::int32_t>(end - begin);
      return 0;
    }
    const std::size_t first = nodes.size();
    nodes[slot].index = static_cast<std::int32_t>(first);
    nodes[slot].count = 0;
    nodes.resize(first + 2);
    if (threads > 1 && end - begin >= kParallelMin) {
      std::vector<BuildNode> left_nodes(1), right_nodes(1);
      const int left_threads = threads / 2;
      int left_depth = 0;
      std::thread worker([&] {
        Bins worker_bins;
        left_depth =
            build(left_nodes, 0, begin, mid, left, depth + 1, left_threads, worker_bins, moved);
      });
      const int right_depth =
          build(right_nodes, 0, mid, end, right, depth + 1, threads - left_threads, bins, moved);
      worker.join();
      splice(nodes, first, left_nodes);
      splice(nodes, first + 1, right_nodes);
      return 1 + std::max(left_depth, right_depth);
    }
    const int left_depth = build(nodes, first, begin, mid, left, depth + 1, 1, bins, moved);
    return 1 + std::max(left_depth,
                        build(nodes, first + 1, mid, end, right, depth + 1, 1, bins, moved));
  }

 private:
  // Puts a subtree built in its own array (root at 0) where the sequential build would have:
  // its root in `slot`, the rest appended, with child indices moved along.
  static void splice(std::vector<BuildNode>& nodes, std::size_t slot,
                     const std::vector<BuildNode>& sub) {
    const std::int32_t shift = static_cast<std::int32_t>(nodes.size()) - 1;
    auto moved = [shift](BuildNode n) {
      if (n.count == 0) n.index += shift;
      return n;
    };
    nodes[slot] = moved(sub[0]);
    for (std::size_t i = 1; i < sub.size(); ++i) nodes.push_back(moved(sub[i]));
  }

  // Partitions [begin, end) into the other array (flipping `moved`) and returns where the
  // second child starts, with the bounds of both sides; `begin` means "make a leaf".
  std::size_t split(std::size_t begin, std::size_t end, const Bounds& set, int depth, Bins& bins,
                    Bounds& left, Bounds& right, bool& moved) {
    std::vector<Ref>& from = moved ? scratch_ : refs_;
    const Box3& box = set.box;
    const Box3& centres = set.centres;
    const std::size_t count = end - begin;
    if (count <= 1) return begin;
    const F4 extent = centres.hi - centres.lo;
    int axis = 0;
    if (extent[1] > extent[axis]) axis = 1;
    if (extent[2] > extent[axis]) axis = 2;
    if (!(extent[axis] > 0)) return begin;  // all centres coincide: nothing to separate
    const bool small = count <= static_cast<std::size_t>(max_leaf_);
    if (depth >= kMedianDepth)
      return small ? begin : median_split(from, begin, end, axis, left, right);

    const int nb = static_cast<int>(std::min<std::size_t>(kBins, count));
    const float last = static_cast<float>(nb - 1);
    for (auto& axis_bins : bins) std::fill_n(axis_bins.begin(), nb, Bin{Box3{}, Box3{}, 0});
    F4 scale = bvh_simd::splat(0.0f);
    for (int a = 0; a < 3; ++a)
      scale[a] = extent[a] > 0 ? static_cast<float>(nb) / extent[a] : 0.0f;
    for (std::size_t i = begin; i < end; ++i) {
      const Ref& r = from[i];
      const F4 c = r.centre2();
      const I4 b = bins_of(c, centres.lo, scale, last);
      for (int a = 0; a < 3; ++a) {
        Bin& bin = bins[a][b[a]];
        bin.box.grow(r.box);
        bin.centres.grow(c);
        ++bin.count;
      }
    }
    // Price each of the nb - 1 planes per axis: sweep from the right, then the left.
    float best_cost = kInf;
    int best_axis = -1, best_bin = 0;
    for (int a = 0; a < 3; ++a) {
      if (!(extent[a] > 0)) continue;
      std::array<float, kBins> right_cost{};
      Box3 acc;
      std::int32_t n = 0;
      for (int b = nb - 1; b > 0; --b) {
        acc.grow(bins[a][b].box);
        n += bins[a][b].count;
        right_cost[b] = n ? acc.area() * static_cast<float>(n) : 0;
      }
      acc = Box3{};
      n = 0;
      for (int b = 0; b < nb - 1; ++b) {
        acc.grow(bins[a][b].box);
        n += bins[a][b].count;
        if (n == 0 || static_cast<std::size_t>(n) == count) continue;
        const float cost = acc.area() * static_cast<float>(n) + right_cost[b + 1];
        if (cost < best_cost) {
          best_cost = cost;
          best_axis = a;
          best_bin = b;
        }
      }
    }
    // Costs in units of one box test per node visit and one primitive test per primitive.
    const float area = box.area();
    if (small) {
      const float split_cost = area > 0 ? 1 + best_cost / area : kInf;
      if (!(static_cast<float>(count) > split_cost)) return begin;
    }
    if (best_axis < 0) return median_split(from, begin, end, axis, left, right);
    for (int b = 0; b < nb; ++b) {
      Bounds& side = b <= best_bin ? left : right;
      side.box.grow(bins[best_axis][b].box);
      side.centres.grow(bins[best_axis][b].centres);
    }
    // Branch-free partition into the other array (the left side keeps its order, the right
    // side is reversed): the side is a coin toss the branch predictor cannot learn.
    std::vector<Ref>& to = moved ? refs_ : scratch_;
    std::size_t to_left = begin, to_right = end;
    for (std::size_t i = begin; i < end; ++i) {
      const Ref& r = from[i];
      // Arithmetic rather than ?: so that the compiler cannot turn it back into a branch.
      const std::size_t is_left =
          bins_of(r.centre2(), centres.lo, scale, last)[best_axis] <= best_bin;
      to[to_right - 1 + is_left * (to_left - to_right + 1)] = r;
      to_left += is_left;
      to_right -= 1 - is_left;
    }
    moved = !moved;
    const std::size_t mid = to_left;
    if (mid == begin || mid == end) return median_split(to, begin, end, axis, left, right);
    return mid;
  }

  static Bounds bounds(const std::vector<Ref>& refs, std::size_t begin, std::size_t end) {
    Bounds b;
    for (std::size_t i = begin; i < end; ++i) {
      b.box.grow(refs[i].box);
      b.centres.grow(refs[i].centre2());
    }
    return b;
  }

  // Halves the set by centre (ties by index): bounds the depth whatever the scene.
  static std::size_t median_split(std::vector<Ref>& refs, std::size_t begin, std::size_t end,
                                  int axis, Bounds& left, Bounds& right) {
    const std::size_t mid = begin + (end - begin) / 2;
    std::nth_element(refs.begin() + begin, refs.begin() + mid, refs.begin() + end,
                     [axis](const Ref& a, const Ref& b) {
                       const float ca = a.centre2()[axis], cb = b.centre2()[axis];
                       return ca < cb || (ca == cb && a.index < b.index);
                     });
    left = bounds(refs, begin, mid);
    right = bounds(refs, mid, end);
    return mid;
  }

  std::vector<Ref>& refs_;
  std::vector<Ref> scratch_;  // threads use disjoint ranges of it, as of refs_
  const int max_leaf_;
};

// Turns the binary tree into W-wide nodes: a node's children are chosen by repeatedly
// opening the inner child of largest area until there are W; its inner children are
// stored side by side, then each is filled in turn, depth first.
template <int W>
class Collapser {
 public:
  using Node = BvhNodeOf<W>;
  Collapser(const std::vector<BuildNode>& tree, std::vector<Node>& nodes, BvhStats& stats,
            const std::vector<std::int32_t>& order, const BvhBuildOptions& options)
      : tree_(tree),
        nodes_(nodes),
        stats_(stats),
        order_(order),
        merge_max_(options.merge_max),
        merge_below_(options.merge_below),
        merge_node_cost_(options.merge_node_cost) {}

  void run() {
    nodes_.reserve(tree_.size() / (W / 2) + 1);
    nodes_.emplace_back();
    clear(nodes_[0]);
    if (tree_[0].count > 0)  // a single leaf: a root with one slot
      set_slot(nodes_[0], 0, tree_[0]);
    else
      emit(0, 0);
    stats_.nodes = static_cast<int>(nodes_.size());
    if (stats_.leaves) stats_.mean_leaf /= stats_.leaves;
  }

 private:
  static void clear(Node& n) {
    for (int i = 0; i < W; ++i) {
      for (int a = 0; a < 3; ++a) {
        n.box[a][i] = kInf;
        n.box[3 + a][i] = -kInf;
      }
      n.child[i] = 0;
      n.count[i] = -1;
    }
  }

  void set_slot(Node& n, int i, const BuildNode& b) {
    for (int a = 0; a < 3; ++a) {
      n.box[a][i] = b.lo[a];
      n.box[3 + a][i] = b.hi[a];
    }
    n.child[i] = b.index;
    n.count[i] = b.count;
    if (b.count > 0) {
      ++stats_.leaves;
      stats_.mean_leaf += b.count;  // a sum until run() ends
    }
  }

  // Fills nodes_[self] (allocated, cleared) with the W-wide node for inner binary node `b`,
  // then its inner children.
  void emit(std::int32_t b, std::int32_t self) {
    std::int32_t kids[W] = {tree_[b].index, tree_[b].index + 1};
    int k = 2;
    while (k < W) {
      int open = -1;
      float best = -1;
      for (int i = 0; i < k; ++i) {
        const BuildNode& c = tree_[kids[i]];
        if (c.count != 0) continue;
        const float area = c.area();
        if (area > best) {
          best = area;
          open = i;
        }
      }
      if (open < 0) break;
      const std::int32_t first = tree_[kids[open]].index;
      kids[open] = first;
      kids[k++] = first + 1;
    }
    // An inner child left unopened over a few cheap primitives becomes one leaf of them
    // all: a node of its own would cost a whole node's bytes for a few boxes.
    struct Merged {
      std::int32_t first = 0, count = 0;  // count 0: not merged
    } merged[W];
    for (int i = 0; i < k && merge_max_ > 1; ++i) {
      if (tree_[kids[i]].count != 0) continue;
      std::int32_t first = 0, n = 0;
      float tests = 0;  // the leaves' primitive tests, weighted by how often a ray meets them
      if (!small_range(kids[i], first, n, tests)) continue;
      // One leaf tests all n whenever its box is met; a node costs a visit there, then
      // each leaf's tests where its own box is met (the surface area heuristic).
      const float area = tree_[kids[i]].area();
      if (static_cast<float>(n) * area <= merge_node_cost_ * area + tests) merged[i] = {first, n};
    }
    // The inner children side by side: one visit's next nodes are close in memory.
    std::int32_t slot[W];
    for (int i = 0; i < k; ++i) {
      slot[i] = -1;
      if (tree_[kids[i]].count == 0 && merged[i].count == 0) {
        slot[i] = static_cast<std::int32_t>(nodes_.size());
        nodes_.emplace_back();
        clear(nodes_.back());
      }
    }
    for (int i = 0; i < k; ++i) {
      BuildNode c = tree_[kids[i]];
      if (merged[i].count > 0) {
        c.index = merged[i].first;
        c.count = merged[i].count;
      } else if (c.count == 0) {
        c.index = slot[i];
      }
      set_slot(nodes_[self], i, c);
    }
    for (int i = 0; i < k; ++i)
      if (slot[i] >= 0) emit(kids[i], slot[i]);
  }

  // Whether the subtree at b holds at most merge_max_ primitives, all below merge_below_,
  // in one run of the leaf order ([first, first + n), as a subtree's leaves always are);
  // adds them to n.
  bool small_range(std::int32_t b, std::int32_t& first, std::int32_t& n, float& tests) const {
    const BuildNode& c = tree_[b];
    if (c.count > 0) {
      if (n == 0) first = c.index;
      if (c.index != first + n || n + c.count > merge_max_) return false;
      for (std::int32_t i = c.index; i < c.index + c.count; ++i)
        if (static_cast<std::size_t>(order_[i]) >= merge_below_) return false;
      n += c.count;
      tests += static_cast<float>(c.count) * c.area();
      return true;
    }
    return small_range(c.index, first, n, tests) && small_range(c.index + 1, first, n, tests);
  }
  const std::vector<BuildNode>& tree_;
  std::vector<Node>& nodes_;
  BvhStats& stats_;
  const std::vector<std::int32_t>& order_;
  const int merge_max_;
  const std::size_t merge_below_;
  const float merge_node_cost_;
};

}  // namespace

int bvh_best_width() {
  static const int width = __builtin_cpu_supports("avx2") ? 8 : 4;
  return width;
}

Bvh build_bvh(std::span<const BvhBox> boxes, const BvhBuildOptions& options) {
  return build_bvh(
      boxes.size(), [&](std::size_t i) { return boxes[i]; }, options);
}

Bvh build_bvh(std::size_t count, const std::function<BvhBox(std::size_t)>& box_of,
              const BvhBuildOptions& options) {
  Bvh bvh;
  if (count == 0 || count > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max() / 4))
    return bvh;
  double scale = 0;
  std::vector<Ref> refs(count);
  for (std::size_t i = 0; i < count; ++i) {
    const BvhBox box = box_of(i);
    for (int a = 0; a < 3; ++a) {
      const double lo = box.lo[a], hi = box.hi[a];
      if (!(lo <= hi)) return bvh;  // NaN or inverted: not for us
      scale = std::max({scale, std::abs(lo), std::abs(hi)});
      refs[i].box.lo[a] = round_down(lo);
      refs[i].box.hi[a] = round_up(hi);
    }
    refs[i].box.lo[3] = refs[i].box.hi[3] = 0;
    refs[i].index = static_cast<std::int32_t>(i);
  }
  if (!(scale < kMaxCoordinate)) return bvh;
  bvh.scale = scale;

  std::vector<BuildNode> tree(1);
  tree.reserve(2 * count);
  Bounds all;
  for (const Ref& r : refs) {
    all.box.grow(r.box);
    all.centres.grow(r.centre2());
  }
  Bins bins;
  const int depth = Builder(refs, std::max(1, options.max_leaf))
                        .build(tree, 0, 0, refs.size(), all, 0, std::max(1, options.threads), bins);

  bvh.order.resize(refs.size());
  for (std::size_t i = 0; i < refs.size(); ++i) bvh.order[i] = refs[i].index;
  std::vector<Ref>().swap(refs);  // its memory can take the nodes (new memory costs)
  if (options.width == 8)
    Collapser<8>(tree, bvh.nodes8, bvh.stats, bvh.order, options).run();
  else
    Collapser<4>(tree, bvh.nodes, bvh.stats, bvh.order, options).run();
  bvh.stats.depth = depth;
  return bvh;
}

}  // namespace rayfarm
