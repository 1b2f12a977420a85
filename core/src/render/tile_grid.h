// The image cut into square tiles: a tile's columns [x0, x1) and rows [r0, r1) (row 0 at
// the top of the image).
#pragma once

#include <algorithm>

namespace rayfarm {

// Side of the square tiles the renderer works in (and the screen bins are made for).
inline constexpr int kTileSize = 32;

struct TileBounds {
  int x0, x1, r0, r1;
  int width() const { return x1 - x0; }
  int rows() const { return r1 - r0; }
};

struct TileGrid {
  int width = 0, height = 0;
  int tiles_x = 0, tiles_y = 0;

  TileGrid(int w, int h)
      : width(w), height(h), tiles_x((w + kTileSize - 1) / kTileSize),
        tiles_y((h + kTileSize - 1) / kTileSize) {}
  int count() const { return tiles_x * tiles_y; }
  TileBounds bounds(int tile) const {
    const int x0 = (tile % tiles_x) * kTileSize, r0 = (tile / tiles_x) * kTileSize;
    return {x0, std::min(x0 + kTileSize, width), r0, std::min(r0 + kTileSize, height)};
  }
};

}  // namespace rayfarm
