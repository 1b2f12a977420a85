// What the hand-computed pixel tests (profile_test, entities_test) share: a 3×3 camera whose
// rays are easy to follow, the two profiles' bytes with a guard against knife edges, and a
// small texture whose every channel differs.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include "test_util.h"

namespace rayfarm::test {

using L = long double;

// 3×3 pixels over a 2×2 window seen from (1, 1, 5): pixel (x, y) looks through the screen
// point (x, y, 0) and meets the wall z = −5 at (2x − 1, 2y − 1, −5). Only the centre ray,
// (0, 0, −1), and the rays of the middle column and row have exact zero components.
inline const std::string kCamera = "camera c { pixeldim 3 3 worlddim 2 2 viewpoint 1 1 5 }\n";

// From the eye (1, 1, 5) to where pixel (x, y) meets the wall z = −5.
inline L wall_distance(int x, int y) {
  return 2 * std::sqrt(L((x - 1) * (x - 1) + (y - 1) * (y - 1) + 25));
}

// Channel c of pixel (x, y), y = 0 the bottom row of the world (the last row of the file).
inline int at(const Image& img, int x, int y, int c) {
  return pixel(img, x, img.height - 1 - y)[c];
}
inline int centre(const Image& img, int c) { return at(img, 1, 1, c); }

// Fails where the byte scale value s is so near a rounding boundary (an integer for
// truncation, a half for rounding) that this test's own arithmetic could decide it.
inline void expect_clear_of_knife_edge(L s) {
  const L frac = s - std::floor(s);
  EXPECT_TRUE(frac > 1e-9L && frac < 1 - 1e-9L) << "knife edge: " << s;
}

// The course's byte: (unsigned char)(v·255) after clamping.
inline int trunc_byte(L v) {
  v = std::clamp(v, L(0), L(1));
  if (v > 0 && v < 1) expect_clear_of_knife_edge(v * 255);
  return static_cast<int>(v * 255);
}

// The lecture's byte: floor(255v + 0.5) after clamping.
inline int round_byte(L v) {
  v = std::clamp(v, L(0), L(1));
  if (v > 0 && v < 1) expect_clear_of_knife_edge(v * 255 + 0.5L);
  return static_cast<int>(std::floor(v * 255 + 0.5L));
}

// A 3×3 texture whose channels all differ; texel (1, 1) is white.
inline Image texture3() {
  Image t(3, 3);
  const int v[27] = {255, 128, 64,  200, 100, 50,  90,  180, 30,  //
                     10,  20,  250, 255, 255, 255, 128, 0,   77,  //
                     33,  66,  99,  150, 160, 170, 240, 230, 220};
  std::copy(v, v + 27, t.rgb.begin());
  return t;
}

// A 4×4 texture, channels 255, 250, ... 20 in file order.
inline Image texture4() {
  Image t(4, 4);
  for (int i = 0; i < 48; ++i) t.rgb[i] = static_cast<std::uint8_t>(255 - 5 * i);
  return t;
}

// Channel c of the texel at (column, file row).
inline int texel(const Image& t, int column, int row, int c) {
  return t.rgb[3 * (row * t.width + column) + c];
}

// The 2009 tiled plane: a floor y = −1 seen from (1, 3, 5) with squares 2 wide in x and 3
// deep in z; `alt`'s diffuse must never show. Pixel (x, y) meets the floor s = 4/(3 − y)
// times (x − 1, y − 3, −5) from the eye.
inline const std::string kFloor2009 = R"(
  camera c { pixeldim 3 3 worlddim 2 2 viewpoint 1 3 5 }
  material m { ambient 5 0 0 diffuse 0 0 4.5 }
  material alt { ambient 0 5 0 diffuse 0 0 9 }
  light { location 1 9 -5 emissivity 1 }
  tiled_plane { material m normal 0 1 0 point 0 -1 0 dimension 2 3 altmaterial alt })";

struct FloorHit {
  L px, pz, path;
};
inline FloorHit floor_hit(int x, int y) {
  const L s = 4.0L / (3 - y);
  const L len = std::sqrt(L((x - 1) * (x - 1) + (y - 3) * (y - 3) + 25));
  return {1 + s * (x - 1), 5 - 5 * s, s * len};
}

// Whether docs/profiles.md §3's 2009 rule puts the plane's own material (the foreground) on the square
// of (px, pz): (int)((x + 10000)/w) + (int)((z + 10000)/h) even. Rows y = 0, 1, 2 of
// kFloor2009 give alt-m-alt, m-alt-m, m-m-m: z decides as much as x.
inline bool foreground_2009(L px, L pz) {
  return (static_cast<long>((px + 10000) / 2) + static_cast<long>((pz + 10000) / 3)) % 2 == 0;
}

// The light (1, 9, −5) seen from the floor hit of pixel (x, y): cos (the normal is y) and d.
inline void floor_light(const FloorHit& h, L& cos, L& d) {
  const L lx = 1 - h.px, ly = 10, lz = -5 - h.pz;
  d = std::sqrt(lx * lx + ly * ly + lz * lz);
  cos = ly / d;
}

}  // namespace rayfarm::test
