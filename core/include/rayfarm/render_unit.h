// A job cut into units for a render farm: each unit a range of tiles, all passes, rendered on
// any node (RenderJob::create with a TileRange), shipped as bytes, and put together into the
// image and statistics the whole render would have given, to the byte: every pixel depends
// on its own position only, and the error estimate adds the tiles' errors in tile order, as
// the whole render does.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rayfarm/image.h"
#include "rayfarm/render.h"

namespace rayfarm {

// What one unit produced.
struct UnitResult {
  int width = 0;  // of the whole image
  int height = 0;
  TileRange range;
  std::vector<std::uint8_t> pixels;   // each tile's rows top to bottom, tiles in order
  std::vector<double> tile_errors;    // per tile (RenderJob::tile_errors)
  bool has_estimate = false;          // the render computes an error estimate at all
  int spp_done = 0;
  int samples_per_pass = 1;
  std::uint64_t primary_rays = 0, shadow_rays = 0, reflection_rays = 0;
  std::vector<std::string> parts;
};

// The result of a finished unit job (`job.finished()` and not canceled).
UnitResult unit_result(const RenderJob& job);

// Binary and versioned ("RFU1"), the pixels deflated; doubles as their IEEE bytes, so the
// estimate comes out as the whole render's. decode_unit() refuses anything malformed with a
// message, never reading past the bytes it is given.
std::string encode_unit(const UnitResult& unit);
std::optional<UnitResult> decode_unit(std::string_view bytes, std::string* error);

// Cuts an image into ranges of about `unit_work` each, where a pixel costs `pixel_work`
// (the same measure: e.g. samples × (bounces + 1)); every range at least one tile.
std::vector<TileRange> plan_units(int width, int height, double pixel_work, double unit_work);

// Puts units together. add() refuses a unit of another image size or one that overlaps
// tiles already added.
class UnitAssembler {
 public:
  UnitAssembler(int width, int height);
  bool add(const UnitResult& unit, std::string* error);
  bool complete() const { return tiles_left_ == 0; }
  const Image& image() const { return image_; }
  // The whole render's statistics (rays, passes, error estimate, parts); times are the
  // caller's to fill in.
  RenderStats stats() const;

 private:
  Image image_;
  int tiles_ = 0;
  int tiles_left_ = 0;
  std::vector<char> have_;
  std::vector<double> tile_errors_;
  bool has_estimate_ = false;
  int spp_done_ = 0;
  int samples_per_pass_ = 1;
  std::uint64_t primary_ = 0, shadow_ = 0, reflection_ = 0;
  std::vector<std::string> parts_;
};

}  // namespace rayfarm
