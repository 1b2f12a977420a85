#include "rayfarm/render_unit.h"

#include <libdeflate.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <memory>

#include "render/tile_grid.h"

namespace rayfarm {
namespace {

constexpr char kMagic[4] = {'R', 'F', 'U', '1'};
// Bounds a hostile header cannot push past: the renderer's own limits.
constexpr int kMaxSide = 1 << 20;
constexpr std::size_t kMaxParts = 64, kMaxPartLength = 64;

class Writer {
 public:
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) u8(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) u8(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
  void bytes(std::string_view s) { out_.append(s); }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

class Reader {
 public:
  explicit Reader(std::string_view in) : in_(in) {}
  bool u8(std::uint8_t& v) {
    if (in_.size() < 1) return false;
    v = static_cast<std::uint8_t>(in_[0]);
    in_.remove_prefix(1);
    return true;
  }
  bool u32(std::uint32_t& v) {
    if (in_.size() < 4) return false;
    v = 0;
    for (int i = 0; i < 4; ++i) v |= std::uint32_t{static_cast<std::uint8_t>(in_[i])} << (8 * i);
    in_.remove_prefix(4);
    return true;
  }
  bool u64(std::uint64_t& v) {
    if (in_.size() < 8) return false;
    v = 0;
    for (int i = 0; i < 8; ++i) v |= std::uint64_t{static_cast<std::uint8_t>(in_[i])} << (8 * i);
    in_.remove_prefix(8);
    return true;
  }
  bool f64(double& v) {
    std::uint64_t u;
    if (!u64(u)) return false;
    v = std::bit_cast<double>(u);
    return true;
  }
  bool bytes(std::size_t n, std::string_view& out) {
    if (in_.size() < n) return false;
    out = in_.substr(0, n);
    in_.remove_prefix(n);
    return true;
  }
  bool empty() const { return in_.empty(); }

 private:
  std::string_view in_;
};

std::size_t range_pixels(const TileGrid& grid, TileRange range) {
  std::size_t n = 0;
  for (int t = range.first; t < range.end; ++t) {
    const TileBounds b = grid.bounds(t);
    n += static_cast<std::size_t>(b.width()) * b.rows();
  }
  return n;
}

bool fail(std::string* error, std::string message) {
  if (error) *error = std::move(message);
  return false;
}

}  // namespace

UnitResult unit_result(const RenderJob& job) {
  const RenderStats st = job.stats();
  UnitResult u;
  u.width = job.width();
  u.height = job.height();
  u.range = job.range();
  u.pixels = job.range_pixels();
  u.tile_errors = job.tile_errors();
  u.has_estimate = st.error_estimate >= 0;
  u.spp_done = st.spp_done;
  u.samples_per_pass = st.samples_per_pass;
  u.primary_rays = st.primary_rays;
  u.shadow_rays = st.shadow_rays;
  u.reflection_rays = st.reflection_rays;
  u.parts = st.parts;
  return u;
}

std::string encode_unit(const UnitResult& u) {
  Writer w;
  w.bytes(std::string_view(kMagic, 4));
  w.u32(static_cast<std::uint32_t>(u.width));
  w.u32(static_cast<std::uint32_t>(u.height));
  w.u32(static_cast<std::uint32_t>(u.range.first));
  w.u32(static_cast<std::uint32_t>(u.range.end));
  w.u8(u.has_estimate ? 1 : 0);
  w.u32(static_cast<std::uint32_t>(u.spp_done));
  w.u32(static_cast<std::uint32_t>(u.samples_per_pass));
  w.u64(u.primary_rays);
  w.u64(u.shadow_rays);
  w.u64(u.reflection_rays);
  w.u32(static_cast<std::uint32_t>(u.parts.size()));
  for (const std::string& p : u.parts) {
    w.u32(static_cast<std::uint32_t>(p.size()));
    w.bytes(p);
  }
  for (double e : u.tile_errors) w.f64(e);
  std::unique_ptr<libdeflate_compressor, decltype(&libdeflate_free_compressor)> c(
      libdeflate_alloc_compressor(1), &libdeflate_free_compressor);
  if (!c) throw std::bad_alloc();
  std::string packed(libdeflate_deflate_compress_bound(c.get(), u.pixels.size()), '\0');
  const std::size_t n = libdeflate_deflate_compress(c.get(), u.pixels.data(), u.pixels.size(),
                                                    packed.data(), packed.size());
  packed.resize(n);
  w.u32(static_cast<std::uint32_t>(packed.size()));
  w.bytes(packed);
  return w.take();
}

std::optional<UnitResult> decode_unit(std::string_view bytes, std::string* error) {
  Reader r(bytes);
  std::string_view magic;
  if (!r.bytes(4, magic) || magic != std::string_view(kMagic, 4)) {
    fail(error, "not a unit result (no RFU1 header)");
    return std::nullopt;
  }
  auto truncated = [&] {
    fail(error, "unit result truncated");
    return std::nullopt;
  };
  UnitResult u;
  std::uint32_t w, h, first, end, spp, spp_pass, nparts;
  std::uint8_t est;
  if (!r.u32(w) || !r.u32(h) || !r.u32(first) || !r.u32(end) || !r.u8(est) || !r.u32(spp) ||
      !r.u32(spp_pass) || !r.u64(u.primary_rays) || !r.u64(u.shadow_rays) ||
      !r.u64(u.reflection_rays) || !r.u32(nparts))
    return truncated();
  if (w < 1 || h < 1 || w > kMaxSide || h > kMaxSide) {
    fail(error, "unit result: bad image size");
    return std::nullopt;
  }
  u.width = static_cast<int>(w);
  u.height = static_cast<int>(h);
  const TileGrid grid(u.width, u.height);
  if (first >= end || end > static_cast<std::uint32_t>(grid.count()) || est > 1 ||
      nparts > kMaxParts || spp > (1u << 30) || spp_pass < 1 || spp_pass > (1u << 30)) {
    fail(error, "unit result: bad header");
    return std::nullopt;
  }
  u.range = {static_cast<int>(first), static_cast<int>(end)};
  u.has_estimate = est == 1;
  u.spp_done = static_cast<int>(spp);
  u.samples_per_pass = static_cast<int>(spp_pass);
  for (std::uint32_t i = 0; i < nparts; ++i) {
    std::uint32_t len;
    std::string_view s;
    if (!r.u32(len)) return truncated();
    if (len > kMaxPartLength) {
      fail(error, "unit result: bad header");
      return std::nullopt;
    }
    if (!r.bytes(len, s)) return truncated();
    u.parts.emplace_back(s);
  }
  u.tile_errors.resize(u.range.count());
  for (double& e : u.tile_errors)
    if (!r.f64(e)) return truncated();
  std::uint32_t packed_size;
  std::string_view packed;
  if (!r.u32(packed_size) || !r.bytes(packed_size, packed)) return truncated();
  if (!r.empty()) {
    fail(error, "unit result: bytes after the pixels");
    return std::nullopt;
  }
  u.pixels.resize(range_pixels(grid, u.range) * 3);
  std::unique_ptr<libdeflate_decompressor, decltype(&libdeflate_free_decompressor)> d(
      libdeflate_alloc_decompressor(), &libdeflate_free_decompressor);
  if (!d) throw std::bad_alloc();
  if (libdeflate_deflate_decompress(d.get(), packed.data(), packed.size(), u.pixels.data(),
                                    u.pixels.size(), nullptr) != LIBDEFLATE_SUCCESS) {
    fail(error, "unit result: the pixels do not inflate to the range's size");
    return std::nullopt;
  }
  return u;
}

std::vector<TileRange> plan_units(int width, int height, double pixel_work, double unit_work) {
  const TileGrid grid(width, height);
  const double tile_work = static_cast<double>(kTileSize) * kTileSize * std::max(pixel_work, 1.0);
  const double wanted = std::ceil(std::max(unit_work, 1.0) / tile_work);
  const int per_unit = static_cast<int>(std::clamp(wanted, 1.0, static_cast<double>(grid.count())));
  std::vector<TileRange> units;
  for (int t = 0; t < grid.count(); t += per_unit)
    units.push_back({t, std::min(t + per_unit, grid.count())});
  return units;
}

UnitAssembler::UnitAssembler(int width, int height)
    : image_(width, height),
      tiles_(TileGrid(width, height).count()),
      tiles_left_(tiles_),
      have_(tiles_, 0),
      tile_errors_(tiles_, 0.0) {}

bool UnitAssembler::add(const UnitResult& u, std::string* error) {
  if (u.width != image_.width || u.height != image_.height)
    return fail(error, "unit of a " + std::to_string(u.width) + "×" + std::to_string(u.height) +
                           " image, not " + std::to_string(image_.width) + "×" +
                           std::to_string(image_.height));
  const TileGrid grid(image_.width, image_.height);
  if (u.range.first < 0 || u.range.first >= u.range.end || u.range.end > tiles_ ||
      u.tile_errors.size() != static_cast<std::size_t>(u.range.count()) ||
      u.pixels.size() != range_pixels(grid, u.range) * 3)
    return fail(error, "unit does not match its tile range");
  for (int t = u.range.first; t < u.range.end; ++t)
    if (have_[t]) return fail(error, "tile " + std::to_string(t) + " was already added");
  if (tiles_left_ < tiles_ &&
      (u.has_estimate != has_estimate_ || u.spp_done != spp_done_ ||
       u.samples_per_pass != samples_per_pass_ || u.parts != parts_))
    return fail(error, "unit rendered with other settings than the units before it");
  has_estimate_ = u.has_estimate;
  spp_done_ = u.spp_done;
  samples_per_pass_ = u.samples_per_pass;
  parts_ = u.parts;
  const std::uint8_t* in = u.pixels.data();
  for (int t = u.range.first; t < u.range.end; ++t) {
    const TileBounds b = grid.bounds(t);
    for (int r = b.r0; r < b.r1; ++r, in += b.width() * 3)
      std::copy_n(in, b.width() * 3, image_.row(r) + b.x0 * 3);
    have_[t] = 1;
    tile_errors_[t] = u.tile_errors[t - u.range.first];
  }
  tiles_left_ -= u.range.count();
  primary_ += u.primary_rays;
  shadow_ += u.shadow_rays;
  reflection_ += u.reflection_rays;
  return true;
}

RenderStats UnitAssembler::stats() const {
  RenderStats st;
  st.primary_rays = primary_;
  st.shadow_rays = shadow_;
  st.reflection_rays = reflection_;
  st.spp_done = spp_done_;
  st.spp_target = spp_done_;
  st.samples_per_pass = samples_per_pass_;
  st.tiles_per_pass = tiles_;
  st.tiles_done = tiles_ - tiles_left_;
  st.parts = parts_;
  if (complete()) {
    st.finished = true;
    st.stop_reason = "spp";
    if (has_estimate_) {
      double total = 0;
      for (double e : tile_errors_) total += e;  // tile order, as the whole render adds them
      st.error_estimate =
          255 * std::sqrt(total / (static_cast<double>(image_.width) * image_.height * 3));
    }
  }
  return st;
}

}  // namespace rayfarm
