#include "image/png_check.h"

#include <libdeflate.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

namespace rayfarm {
namespace {

std::uint32_t be32(std::string_view bytes, std::size_t at) {
  std::uint32_t value = 0;
  for (std::size_t i = 0; i < 4; ++i)
    value = value << 8 | static_cast<unsigned char>(bytes[at + i]);
  return value;
}

std::string problem(std::string what) { return "corrupt PNG: " + what; }

struct Header {
  std::uint64_t width = 0, height = 0;
  int depth = 0, colour = 0, interlace = 0;
  int channels() const { return colour == 2 ? 3 : colour == 4 ? 2 : colour == 6 ? 4 : 1; }
  std::uint64_t row_bytes(std::uint64_t pixels) const {
    return (pixels * static_cast<std::uint64_t>(channels() * depth) + 7) / 8;
  }
};

const char* colour_name(int colour) {
  switch (colour) {
    case 0: return "grey";
    case 2: return "RGB";
    case 3: return "palette";
    case 4: return "grey with alpha";
    default: return "RGB with alpha";
  }
}

std::optional<std::string> header_problem(std::string_view ihdr, Header& h) {
  h.width = be32(ihdr, 0);
  h.height = be32(ihdr, 4);
  h.depth = static_cast<unsigned char>(ihdr[8]);
  h.colour = static_cast<unsigned char>(ihdr[9]);
  const int compression = static_cast<unsigned char>(ihdr[10]);
  const int filter = static_cast<unsigned char>(ihdr[11]);
  h.interlace = static_cast<unsigned char>(ihdr[12]);
  const char* depths = nullptr;  // the bit depths the format allows with this colour type
  bool allowed = false;
  switch (h.colour) {
    case 0:
      depths = "1, 2, 4, 8 or 16";
      allowed = h.depth == 1 || h.depth == 2 || h.depth == 4 || h.depth == 8 || h.depth == 16;
      break;
    case 3:
      depths = "1, 2, 4 or 8";
      allowed = h.depth == 1 || h.depth == 2 || h.depth == 4 || h.depth == 8;
      break;
    case 2:
    case 4:
    case 6:
      depths = "8 or 16";
      allowed = h.depth == 8 || h.depth == 16;
      break;
    default:
      return problem("colour type " + std::to_string(h.colour) +
                     " does not exist (0, 2, 3, 4 or 6)");
  }
  if (!allowed) {
    return problem("bit depth " + std::to_string(h.depth) + " is not allowed with colour type " +
                   std::to_string(h.colour) + " (" + colour_name(h.colour) + "): " + depths);
  }
  if (compression != 0)
    return problem("compression method " + std::to_string(compression) + " does not exist (0)");
  if (filter != 0)
    return problem("filter method " + std::to_string(filter) + " does not exist (0)");
  if (h.interlace > 1) {
    return problem("interlace method " + std::to_string(h.interlace) +
                   " does not exist (0 or 1)");
  }
  return std::nullopt;
}

// A reduced image of the scan: Adam7's seven passes, or the whole image.
struct Pass {
  std::uint64_t x0, y0, dx, dy, width, height;
};

std::vector<Pass> passes(const Header& h) {
  if (h.interlace == 0) return {{0, 0, 1, 1, h.width, h.height}};
  static constexpr std::array<std::array<int, 4>, 7> kAdam7{
      {{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4},
       {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}}};
  std::vector<Pass> out;
  for (const auto& [x0, y0, dx, dy] : kAdam7) {
    const std::uint64_t w = h.width > static_cast<std::uint64_t>(x0)
                                ? (h.width - x0 + dx - 1) / dx : 0;
    const std::uint64_t ht = h.height > static_cast<std::uint64_t>(y0)
                                 ? (h.height - y0 + dy - 1) / dy : 0;
    if (w > 0 && ht > 0) out.push_back({std::uint64_t(x0), std::uint64_t(y0), std::uint64_t(dx),
                                        std::uint64_t(dy), w, ht});
  }
  return out;
}

unsigned char paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return static_cast<unsigned char>(pa <= pb && pa <= pc ? a : pb <= pc ? b : c);
}

// Undoes a row's filter in place (`prev`: the row above, already undone, or null).
void unfilter(int type, unsigned char* row, const unsigned char* prev, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    const int a = i > 0 ? row[i - 1] : 0, b = prev ? prev[i] : 0;
    const int c = i > 0 && prev ? prev[i - 1] : 0;
    switch (type) {
      case 1: row[i] = static_cast<unsigned char>(row[i] + a); break;
      case 2: row[i] = static_cast<unsigned char>(row[i] + b); break;
      case 3: row[i] = static_cast<unsigned char>(row[i] + (a + b) / 2); break;
      case 4: row[i] = static_cast<unsigned char>(row[i] + paeth(a, b, c)); break;
      default: break;
    }
  }
}

// Rows' filter types, and (for a palette image) every index against the palette's length.
std::optional<std::string> scan_problem(const Header& h, unsigned char* raw, std::size_t palette) {
  for (const Pass& p : passes(h)) {
    const std::uint64_t n = h.row_bytes(p.width);
    const unsigned char* prev = nullptr;
    for (std::uint64_t y = 0; y < p.height; ++y, raw += n + 1) {
      const int filter = raw[0];
      if (filter > 4) {
        return problem("row " + std::to_string(p.y0 + y * p.dy) + " has filter type " +
                       std::to_string(filter) + ", which does not exist (0-4)");
      }
      if (h.colour != 3) continue;
      unsigned char* row = raw + 1;
      unfilter(filter, row, prev, n);
      prev = row;
      const unsigned mask = (1u << h.depth) - 1;
      for (std::uint64_t x = 0; x < p.width; ++x) {
        const std::uint64_t bit = x * h.depth;
        const unsigned index = row[bit / 8] >> (8 - h.depth - bit % 8) & mask;
        if (index >= palette) {
          return problem("palette index " + std::to_string(index) + " at pixel (" +
                         std::to_string(p.x0 + x * p.dx) + ", " +
                         std::to_string(p.y0 + y * p.dy) + ") is past the palette's " +
                         std::to_string(palette) + " colours");
        }
      }
    }
  }
  return std::nullopt;
}

// A chunk type for a message: as written when it is four letters, as the format requires.
std::string type_text(std::string_view type) {
  for (char c : type)
    if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'))) return "with a damaged type";
  return std::string(type);
}

}  // namespace

std::optional<std::string> png_integrity_problem(std::string_view png, std::size_t max_inflated) {
  Header h;
  std::string idat;
  std::size_t palette = 0;
  bool has_palette = false, ended = false;
  for (std::size_t at = 8; png.size() - at >= 12;) {
    const std::uint32_t length = be32(png, at);
    if (length > png.size() - at - 12) break;  // cut short: the decoder says so
    const std::string_view type = png.substr(at + 4, 4), data = png.substr(at + 8, length);
    if (type == "IEND") {  // (its CRC guards nothing: the pixels are all before it)
      ended = true;
      break;
    }
    if (libdeflate_crc32(0, png.data() + at + 4, length + 4) != be32(png, at + 8 + length)) {
      // An ancillary chunk (lower-case first letter) is only skipped, as libpng skips it:
      // the pixels do not depend on it.
      if (!(type[0] & 0x20)) {
        return problem("chunk " + type_text(type) + " at byte " + std::to_string(at) +
                       " fails its CRC check (the file is damaged)");
      }
    } else if (at == 8) {
      if (auto p = header_problem(data, h)) return p;
    } else if (type == "PLTE") {
      palette = length / 3;
      has_palette = true;
    } else if (type == "IDAT") {
      idat.append(data);
    }
    at += 12 + std::size_t{length};
  }
  // Cut short, or no image data: the decoder's messages say so.
  if (!ended || idat.empty() || h.depth == 0) return std::nullopt;
  if (h.colour == 3 && !has_palette)
    return problem("a palette image (colour type 3) has no PLTE chunk");
  if (h.colour == 3 && palette == 0) return problem("the PLTE chunk holds no colours");
  // (The caller has bounded the size; this only keeps the sums below from overflowing.)
  if (h.width * h.height > (std::uint64_t{1} << 40)) return std::nullopt;

  std::uint64_t raw_size = 0;
  for (const Pass& p : passes(h)) raw_size += p.height * (1 + h.row_bytes(p.width));
  std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor*)> inflater(
      libdeflate_alloc_decompressor(), libdeflate_free_decompressor);
  if (!inflater) return std::nullopt;
  // Room for one byte more than the image needs; data running on past it (which decoders
  // accept, as libpng does with a warning) is inflated again into as much room as the
  // decoder itself would allow, so that its Adler-32 and indices are still checked.
  std::unique_ptr<unsigned char[]> raw;
  std::size_t used = 0, produced = 0;
  libdeflate_result r = LIBDEFLATE_INSUFFICIENT_SPACE;
  const std::uint64_t most = std::max<std::uint64_t>(raw_size + 1, max_inflated);
  for (const std::uint64_t room : {raw_size + 1, most}) {
    raw.reset(new (std::nothrow) unsigned char[room]);
    if (!raw) return std::nullopt;
    r = libdeflate_zlib_decompress_ex(inflater.get(), idat.data(), idat.size(), raw.get(), room,
                                      &used, &produced);
    if (r != LIBDEFLATE_INSUFFICIENT_SPACE) break;
  }
  if (r == LIBDEFLATE_INSUFFICIENT_SPACE) return std::nullopt;
  if (r != LIBDEFLATE_SUCCESS) {
    return problem("the image data does not inflate (its zlib stream is damaged or fails its "
                   "Adler-32 check)");
  }
  if (produced < raw_size) {
    return problem("the image data holds " + std::to_string(produced) + " bytes of the " +
                   std::to_string(raw_size) + " its size needs");
  }
  return scan_problem(h, raw.get(), palette);
}

}  // namespace rayfarm
