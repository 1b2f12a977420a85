// Light buffer construction: each sphere's widened box is projected onto the faces of the
// direction cube it can be seen through, its cells get an entry, and each cell's entries
// are sorted by how near the light they begin.
#include "accel/light_buffer.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

namespace rayfarm {
namespace {

// Face coordinates are in [-1, 1]; their rounding is about 1e-16, so this pad is ample.
constexpr double kFacePad = 1e-9;

// How many spheres ahead of the one in hand the build asks for: enough to cover a miss with
// a sphere's few dozen operations each.
constexpr std::size_t kAhead = 16;

// The cell along one side holding face coordinate u. Monotonic in u, and the same function
// for building and looking up, so a coordinate within kFacePad of a sphere's range gets one
// of its cells. (Truncation is floor here: below 0 both are clamped to cell 0.)
inline int cell_of(double u, int n) {
  u = std::clamp(u, -2.0, 2.0);  // also keeps the int conversion in range
  const int c = static_cast<int>((u + 1.0) * (0.5 * n));
  return std::clamp(c, 0, n - 1);
}

// The face a direction from the light points into (+x, -x, +y, -y, +z, -z), the magnitude of
// its major coordinate and its two face coordinates (not yet divided). Ties go to the lower
// axis; a sphere straddling a face edge is entered on both faces, so either is right.
struct FaceCoords {
  int face;
  double major, a, b;
};
inline FaceCoords face_coords(const glm::dvec3& v) {
  const double ax = std::abs(v.x), ay = std::abs(v.y), az = std::abs(v.z);
  if (ax >= ay && ax >= az) return {v.x >= 0 ? 0 : 1, ax, v.y, v.z};
  if (ay >= az) return {v.y >= 0 ? 2 : 3, ay, v.x, v.z};
  return {v.z >= 0 ? 4 : 5, az, v.x, v.y};
}

// The two minor axes of a face's major axis, in the order face_coords reports them.
constexpr int kMinor[3][2] = {{1, 2}, {0, 2}, {0, 1}};

struct Rect {
  std::int32_t sphere;
  std::uint8_t face;
  std::uint16_t a0, a1, b0, b1;  // inclusive cell ranges
};

// The cell rectangles of a sphere's box [lo, hi] (not containing the light) on every face it
// can be seen through. `clip`: no point of the sphere inside a face's pyramid has a major
// coordinate below it (there |X - L| <= sqrt(3) * major, and |X - L| >= the sphere's near).
void face_rects(std::int32_t sphere, const glm::dvec3& lo, const glm::dvec3& hi,
                const glm::dvec3& light, double clip, int n, std::vector<Rect>& out) {
  for (int k = 0; k < 3; ++k) {
    for (int sign = 0; sign < 2; ++sign) {
      double xlo = sign == 0 ? lo[k] - light[k] : light[k] - hi[k];
      const double xhi = sign == 0 ? hi[k] - light[k] : light[k] - lo[k];
      if (!(xhi >= clip)) continue;
      xlo = std::max(xlo, clip);
      int range[2][2];
      bool visible = true;
      for (int m = 0; m < 2 && visible; ++m) {
        const int u = kMinor[k][m];
        const double ylo = lo[u] - light[u], yhi = hi[u] - light[u];
        // y / x over the box is extreme at its corners (x > 0 throughout).
        const double amin = std::min(ylo / xlo, ylo / xhi) - kFacePad;
        const double amax = std::max(yhi / xlo, yhi / xhi) + kFacePad;
        if (amax < -1 || amin > 1) visible = false;
        range[m][0] = cell_of(amin, n);
        range[m][1] = cell_of(amax, n);
      }
      if (!visible) continue;
      out.push_back({sphere, static_cast<std::uint8_t>(2 * k + sign),
                     static_cast<std::uint16_t>(range[0][0]), static_cast<std::uint16_t>(range[0][1]),
                     static_cast<std::uint16_t>(range[1][0]), static_cast<std::uint16_t>(range[1][1])});
    }
  }
}

}  // namespace

bool LightBuffer::lookup(const glm::dvec3& p, Cell& cell) const {
  if (!(std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) <= reach)) return false;
  const glm::dvec3 v = p - light;
  const FaceCoords f = face_coords(v);
  if (!(f.major > 0)) return false;
  // The segment from p to the light stays within |v| of the light.
  cell.limit_sq = glm::dot(v, v) * (1 + 1e-12);
  const std::int32_t base = face_base[f.face];
  if (base < 0) {
    cell.begin = cell.end = nullptr;
    return true;
  }
  // One reciprocal for both coordinates: its rounding is far inside kFacePad.
  const double inv = 1 / f.major;
  const std::size_t c = static_cast<std::size_t>(base) +
                        static_cast<std::size_t>(cell_of(f.a * inv, n)) * n +
                        cell_of(f.b * inv, n);
  cell.begin = entries.data() + start[c];
  cell.end = entries.data() + start[c + 1];
  __builtin_prefetch(cell.begin);  // the caller reads it after other work
  return true;
}

LightBuffer build_light_buffer(const glm::dvec3& light, std::span<const WidenedSphere> spheres,
                               double reach, const LightBufferLimits& limits) {
  LightBuffer lb;
  if (spheres.empty() || !std::isfinite(reach)) return lb;
  lb.light = light;
  lb.reach = reach;

  // Near distances and apparent sizes; spheres about the light go to `around`.
  std::vector<float> near(spheres.size());
  std::vector<double> sizes;
  sizes.reserve(spheres.size());
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    const double rr = spheres[i].radius;
    const double dist = glm::length(spheres[i].centre - light);
    const double d = dist - rr;
    if (!(d > 0) || !std::isfinite(dist)) {
      lb.around.push_back(static_cast<std::int32_t>(i));
      if (lb.around.size() > limits.max_around) return {};
      near[i] = -std::numeric_limits<float>::infinity();
      continue;
    }
    near[i] = float_down(d);
    sizes.push_back(2 * rr / dist);
  }

  // Cells about twice as wide as the median sphere looks from the light (face coordinates
  // span 2): finer cells list fewer spheres each but cost more to build and to look up,
  // and measured no faster on the benchmark scenes.
  int n = 1;
  if (!sizes.empty()) {
    auto mid = sizes.begin() + static_cast<std::ptrdiff_t>(sizes.size() / 2);
    std::nth_element(sizes.begin(), mid, sizes.end());
    const double cells = std::ceil(1 / *mid);
    n = static_cast<int>(std::clamp(cells, 1.0, static_cast<double>(limits.max_cells_per_side)));
  }

  // Rectangles sphere by sphere, nearest first, so that every cell is filled nearest first.
  const std::vector<std::int32_t> order = order_by_near(near);
  std::vector<Rect> rects;
  rects.reserve(order.size() + order.size() / 2);  // most spheres show on one or two faces
  for (;;) {
    rects.clear();
    double total = 0;
    for (std::size_t k = 0; k < order.size(); ++k) {
      // Nearest first is no order in memory: each sphere's record would be a wait of its own
      // (two fifths of the build's samples in a run of shallow-60k; docs/performance.md).
      if (k + kAhead < order.size()) {
        __builtin_prefetch(&spheres[order[k + kAhead]]);
        __builtin_prefetch(&near[order[k + kAhead]]);
      }
      const std::int32_t i = order[k];
      if (near[i] == -std::numeric_limits<float>::infinity()) continue;
      const double rr = spheres[i].radius;
      const glm::dvec3 lo = spheres[i].centre - rr, hi = spheres[i].centre + rr;
      const double clip = static_cast<double>(near[i]) / std::sqrt(3.0) * (1 - 1e-9);
      const std::size_t first = rects.size();
      face_rects(i, lo, hi, light, clip, n, rects);
      for (std::size_t r = first; r < rects.size(); ++r)
        total += (rects[r].a1 - rects[r].a0 + 1.0) * (rects[r].b1 - rects[r].b0 + 1.0);
    }
    if (total <= limits.max_entries_per_sphere * static_cast<double>(spheres.size()) || n == 1) {
      if (total > 0xFFFFFFF0u) return {};
      break;
    }
    n = std::max(1, n / 2);
  }
  lb.n = n;

  // Cells only for the faces that hold anything.
  const std::size_t face_cells = static_cast<std::size_t>(n) * n;
  bool used[6] = {};
  for (const Rect& r : rects) used[r.face] = true;
  std::size_t cells = 0;
  for (int f = 0; f < 6; ++f) {
    lb.face_base[f] = used[f] ? static_cast<std::int32_t>(cells) : -1;
    if (used[f]) cells += face_cells;
  }
  auto for_cells = [&](const Rect& r, auto&& fn) {
    const std::size_t base = static_cast<std::size_t>(lb.face_base[r.face]);
    for (int a = r.a0; a <= r.a1; ++a)
      for (int b = r.b0; b <= r.b1; ++b) fn(base + static_cast<std::size_t>(a) * n + b);
  };
  // Counts two places on, so that the sums leave start[c + 1] where cell c begins; filling
  // moves it to where c ends, which is where c + 1 begins. No second array as large as
  // `start` (6 MB at 512 cells a side) to fill from.
  lb.start.assign(cells + 2, 0);
  for (const Rect& r : rects) for_cells(r, [&](std::size_t c) { ++lb.start[c + 2]; });
  for (std::size_t c = 2; c <= cells + 1; ++c) lb.start[c] += lb.start[c - 1];
  lb.entries.resize(lb.start[cells + 1]);
  for (const Rect& r : rects)
    for_cells(r, [&](std::size_t c) {
      lb.entries[lb.start[c + 1]++] = {r.sphere, near[r.sphere]};
    });
  lb.start.pop_back();
  return lb;
}

}  // namespace rayfarm
