// Encoding PNG (here, with libdeflate) and decoding it (through the stb wrapper), and PPM
// (here: the format is tiny).
#include "rayfarm/image_io.h"

#include <libdeflate.h>

#include <algorithm>
#include <climits>
#include <cstdint>
#include <memory>
#include <new>
#include <stdexcept>

#include "image/png_check.h"
#include "image/stb_wrappers.h"

namespace rayfarm {
namespace {

constexpr std::string_view kPngSignature("\x89PNG\r\n\x1a\n", 8);

std::string size_text(long long width, long long height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

std::optional<Image> fail(std::string* error, std::string message) {
  if (error) *error = std::move(message);
  return std::nullopt;
}

void check_buffer(const Image& image) {
  if (image.width < 0 || image.height < 0 ||
      image.rgb.size() != static_cast<std::size_t>(image.width) * image.height * 3) {
    throw std::invalid_argument("image buffer of " + std::to_string(image.rgb.size()) +
                                " bytes does not match its size " +
                                size_text(image.width, image.height));
  }
}

// Checked before anything is allocated for the pixels. Each side is below 2^32, so the
// product cannot overflow.
std::optional<std::string> size_problem(std::uint64_t width, std::uint64_t height,
                                        long long max_pixels) {
  if (width == 0 || height == 0) return "image has no pixels (" + size_text(width, height) + ")";
  const std::uint64_t most = static_cast<std::uint64_t>(std::clamp(max_pixels, 1LL, kMaxDecodePixels));
  if (width * height > most) {
    return "image too large: " + size_text(width, height) + " is over the limit of " +
           std::to_string(most) + " pixels";
  }
  return std::nullopt;
}

std::uint32_t read_be32(std::string_view bytes, std::size_t at) {
  std::uint32_t value = 0;
  for (std::size_t i = 0; i < 4; ++i)
    value = value << 8 | static_cast<unsigned char>(bytes[at + i]);
  return value;
}

// stb_image memcpy()s from a null pointer for an empty IDAT chunk before any image data
// (undefined behaviour, found by fuzzing). Empty IDATs carry nothing: the copy drops them all.
std::optional<std::string> without_empty_idats(std::string_view png) {
  std::string out;
  std::size_t copied = 0;                            // bytes of `png` already in `out`
  for (std::size_t at = 8; png.size() - at >= 8;) {  // 8: a chunk's length and type
    std::uint64_t end = at + 12 + std::uint64_t{read_be32(png, at)};  // after its CRC
    if (end == at + 12 && png.substr(at + 4, 4) == "IDAT") {
      out.append(png.substr(copied, at - copied));
      copied = std::min<std::uint64_t>(end, png.size());
    }
    if (end > png.size()) break;
    at = end;
  }
  if (copied == 0) return std::nullopt;
  out.append(png.substr(copied));
  return out;
}

std::size_t png_alloc_limit(std::size_t file_bytes, std::uint64_t width, std::uint64_t height) {
  const std::size_t raw = width * height * 8 + height;
  return std::max(2 * file_bytes, 2 * raw) + 65536;
}

std::optional<Image> decode_png(std::string_view bytes, std::string* error, long long max_pixels) {
  // IHDR is read here so that a hostile size is refused before stb allocates anything.
  if (bytes.size() < 8 + 8 + 13 || read_be32(bytes, 8) != 13 || bytes.substr(12, 4) != "IHDR") {
    return fail(error, "corrupt PNG: no IHDR chunk after the signature");
  }
  std::uint64_t width = read_be32(bytes, 16);
  std::uint64_t height = read_be32(bytes, 20);
  if (auto problem = size_problem(width, height, max_pixels)) return fail(error, *problem);
  if (bytes.size() > INT_MAX) return fail(error, "PNG file too large to decode");
  // No legitimate stb allocation exceeds twice the input (the IDAT buffer doubles) or twice
  // the raw image at its widest (16-bit RGBA plus a filter byte per row; inflate doubles).
  std::size_t alloc_limit = png_alloc_limit(bytes.size(), width, height);
  if (auto problem = png_integrity_problem(bytes, alloc_limit)) return fail(error, *problem);
  auto cleaned = without_empty_idats(bytes);
  if (cleaned) bytes = *cleaned;
  alloc_limit = png_alloc_limit(bytes.size(), width, height);
  auto png = stb::decode_png_rgb(reinterpret_cast<const unsigned char*>(bytes.data()),
                                 static_cast<int>(bytes.size()), alloc_limit);
  if (png.rgb.empty()) {
    // With the limit above, running out of memory almost always means hostile sizes.
    if (png.error == "outofmem") return fail(error, "cannot decode PNG: data larger than its size");
    // stb_image's reasons are terse codes ("outofdata"), and some damage has none: a file
    // that does not end with its IEND chunk was cut short, whatever stb met first.
    constexpr std::string_view kIend("\0\0\0\0IEND\xae\x42\x60\x82", 12);
    if (!bytes.ends_with(kIend))
      return fail(error, "cannot decode PNG: the file is cut short (it does not end with the "
                         "IEND chunk)");
    return fail(error, "cannot decode PNG: the data is damaged" +
                           (png.error.empty() ? std::string() : " (" + png.error + ")"));
  }
  Image image;
  image.width = png.width;
  image.height = png.height;
  image.rgb = std::move(png.rgb);
  return image;
}

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

// A decimal number in a PPM header or P3 body, after whitespace and '#' comments.
struct PpmNumber {
  enum Kind { ok, missing, malformed } kind;
  std::uint64_t value;  // saturates at UINT32_MAX, so that width * height cannot overflow
  std::string_view text = {};  // as written (up to white space), for messages
};

// A token for a message: at most 20 characters.
std::string shown(std::string_view text) {
  return "'" + std::string(text.substr(0, 20)) + (text.size() > 20 ? "...'" : "'");
}

PpmNumber read_number(std::string_view s, std::size_t& pos) {
  while (pos < s.size() && (is_space(s[pos]) || s[pos] == '#')) {
    if (s[pos] == '#') {
      while (pos < s.size() && s[pos] != '\n' && s[pos] != '\r') ++pos;
    } else {
      ++pos;
    }
  }
  if (pos == s.size()) return {PpmNumber::missing, 0};
  std::uint64_t value = 0;
  std::size_t start = pos;
  for (; pos < s.size() && s[pos] >= '0' && s[pos] <= '9'; ++pos) {
    value = std::min<std::uint64_t>(value * 10 + (s[pos] - '0'), UINT32_MAX);
  }
  std::size_t end = pos;
  while (end < s.size() && !is_space(s[end]) && s[end] != '#') ++end;
  const std::string_view text = s.substr(start, end - start);
  if (pos == start || pos != end) return {PpmNumber::malformed, 0, text};
  return {PpmNumber::ok, value, text};
}

std::optional<Image> decode_ppm(std::string_view s, std::string* error, long long max_pixels) {
  bool ascii = s[1] == '3';
  std::size_t pos = 2;
  if (pos < s.size() && !is_space(s[pos]) && s[pos] != '#') {
    return fail(error, "bad PPM header: no whitespace after P" + std::string(1, s[1]));
  }
  std::uint64_t fields[3];  // width, height, maxval
  std::string_view maxval_text;  // as written: a value past 2^32 is read saturated
  const char* names[3] = {"width", "height", "maxval"};
  for (int i = 0; i < 3; ++i) {
    PpmNumber number = read_number(s, pos);
    if (number.kind == PpmNumber::missing) {
      return fail(error, std::string("truncated PPM header: no ") + names[i]);
    }
    if (number.kind == PpmNumber::malformed) {
      return fail(error, std::string("bad PPM header: ") + names[i] + " " + shown(number.text) +
                             " is not a whole number");
    }
    if (number.value == UINT32_MAX && i < 2)  // saturated: the size message would be wrong
      return fail(error, std::string("bad PPM header: ") + names[i] + " " + shown(number.text) +
                             " is far too large");
    fields[i] = number.value;
    maxval_text = number.text;
  }
  std::uint64_t width = fields[0], height = fields[1], maxval = fields[2];
  if (auto problem = size_problem(width, height, max_pixels)) return fail(error, *problem);
  if (maxval < 1 || maxval > 65535) {
    return fail(error, "bad PPM header: maxval " + std::string(maxval_text.substr(0, 20)) +
                           " is not in 1..65535");
  }
  std::vector<std::uint8_t> to_8bit(maxval + 1);
  for (std::uint64_t v = 0; v <= maxval; ++v) to_8bit[v] = (v * 255 + maxval / 2) / maxval;
  // The sample as written: a value past 2^32 is read saturated.
  auto too_big = [&](const std::string& sample) {
    return fail(error, "PPM sample " + sample + " exceeds maxval " + std::to_string(maxval));
  };

  std::uint64_t samples = width * height * 3;
  Image image;
  image.width = static_cast<int>(width);
  image.height = static_cast<int>(height);
  if (ascii) {
    // Grown as samples arrive, so a short file cannot make us allocate for its claimed size.
    image.rgb.reserve(std::min<std::uint64_t>(samples, (s.size() - pos) / 2 + 1));
    while (image.rgb.size() < samples) {
      PpmNumber number = read_number(s, pos);
      if (number.kind == PpmNumber::missing) {
        return fail(error, "truncated PPM data: expected " + std::to_string(samples) +
                               " samples, got " + std::to_string(image.rgb.size()));
      }
      if (number.kind == PpmNumber::malformed) {
        return fail(error, "bad PPM data: sample " + std::to_string(image.rgb.size() + 1) + ", " +
                               shown(number.text) + ", is not a whole number");
      }
      if (number.value > maxval) {
        const std::string text(number.text.substr(0, 20));
        return too_big(number.text.size() > 20 ? text + "..." : text);
      }
      image.rgb.push_back(to_8bit[number.value]);
    }
    return image;
  }

  // Exactly one whitespace character separates maxval from binary data.
  if (pos == s.size() || !is_space(s[pos])) {
    return fail(error, "bad PPM header: no whitespace after maxval");
  }
  ++pos;
  std::uint64_t sample_bytes = maxval > 255 ? 2 : 1;
  std::uint64_t expected = samples * sample_bytes;
  if (s.size() - pos < expected) {
    return fail(error, "truncated PPM data: expected " + std::to_string(expected) + " bytes, got " +
                           std::to_string(s.size() - pos));
  }
  image.rgb.resize(samples);
  const auto* data = reinterpret_cast<const unsigned char*>(s.data() + pos);
  for (std::uint64_t i = 0; i < samples; ++i) {
    std::uint64_t v = sample_bytes == 2 ? (data[2 * i] << 8 | data[2 * i + 1]) : data[i];
    if (v > maxval) return too_big(std::to_string(v));
    image.rgb[i] = to_8bit[v];
  }
  return image;
}

}  // namespace

std::vector<unsigned char> encode_png(const Image& image) {
  check_buffer(image);
  if (image.width == 0 || image.height == 0) {
    throw std::invalid_argument("a PNG cannot hold an empty image (" +
                                size_text(image.width, image.height) + ")");
  }
  // One IDAT chunk, whose length field is 31 bits: stay well clear.
  const std::size_t row = 3 * static_cast<std::size_t>(image.width);
  const std::size_t filtered_size = (row + 1) * image.height;
  if (filtered_size > (std::size_t{1} << 30)) {
    throw std::invalid_argument("image too large for PNG encoding: " +
                                size_text(image.width, image.height));
  }
  // Every row with the "up" filter (the first row's "up" is its bytes as they are): on
  // rendered images it compresses best of the five for the least work. These are the bytes
  // the stb_image_write encoder with its filter forced to "up" and libdeflate at level 1 wrote
  // before; one buffer for the filtered rows and one for the file, nothing copied twice.
  std::vector<unsigned char> filtered(filtered_size);
  for (int y = 0; y < image.height; ++y) {
    unsigned char* out = filtered.data() + y * (row + 1);
    const std::uint8_t* cur = image.row(y);
    out[0] = 2;
    if (y == 0) {
      std::copy(cur, cur + row, out + 1);
    } else {
      const std::uint8_t* up = image.row(y - 1);
      for (std::size_t i = 0; i < row; ++i) out[1 + i] = static_cast<unsigned char>(cur[i] - up[i]);
    }
  }
  using Compressor = std::unique_ptr<libdeflate_compressor, decltype(&libdeflate_free_compressor)>;
  Compressor compressor(libdeflate_alloc_compressor(1), &libdeflate_free_compressor);
  if (!compressor) throw std::bad_alloc();
  const std::size_t bound = libdeflate_zlib_compress_bound(compressor.get(), filtered_size);
  constexpr std::size_t kHeader = 8 + 12 + 13 + 8;  // signature, IHDR, IDAT's length and type
  std::vector<unsigned char> png(kHeader + bound + 4 + 12);
  auto store32 = [](unsigned char* at, std::uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) *at++ = static_cast<unsigned char>(v >> shift);
  };
  unsigned char* o = png.data();
  auto put32 = [&o, &store32](std::uint32_t v) {
    store32(o, v);
    o += 4;
  };
  // A chunk's CRC covers its type and data, from `type` up to where `o` is now.
  auto put_crc = [&o, &put32](const unsigned char* type) {
    put32(libdeflate_crc32(0, type, static_cast<std::size_t>(o - type)));
  };
  o = std::copy(kPngSignature.begin(), kPngSignature.end(), o);
  put32(13);
  unsigned char* type = o;
  o = std::copy_n("IHDR", 4, o);
  put32(static_cast<std::uint32_t>(image.width));
  put32(static_cast<std::uint32_t>(image.height));
  *o++ = 8;  // bits per sample
  *o++ = 2;  // RGB
  *o++ = 0;  // deflate
  *o++ = 0;  // adaptive filtering
  *o++ = 0;  // not interlaced
  put_crc(type);
  unsigned char* length = o;
  o += 4;
  type = o;
  o = std::copy_n("IDAT", 4, o);
  const std::size_t zlen =
      libdeflate_zlib_compress(compressor.get(), filtered.data(), filtered_size, o, bound);
  if (zlen == 0) throw std::bad_alloc();  // within the bound it cannot fail
  o += zlen;
  store32(length, static_cast<std::uint32_t>(zlen));
  put_crc(type);
  put32(0);
  type = o;
  o = std::copy_n("IEND", 4, o);
  put_crc(type);
  png.resize(static_cast<std::size_t>(o - png.data()));
  return png;
}

std::vector<unsigned char> encode_ppm(const Image& image) {
  check_buffer(image);
  std::string header =
      "P6\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n255\n";
  std::vector<unsigned char> out;
  out.reserve(header.size() + image.rgb.size());
  out.insert(out.end(), header.begin(), header.end());
  out.insert(out.end(), image.rgb.begin(), image.rgb.end());
  return out;
}

std::vector<unsigned char> encode_image(const Image& image, ImageFormat format) {
  return format == ImageFormat::ppm ? encode_ppm(image) : encode_png(image);
}

std::uint64_t decode_memory_bound(std::string_view bytes) {
  if (bytes.starts_with(kPngSignature) && bytes.size() >= 24) {
    const std::uint64_t width = read_be32(bytes, 16), height = read_be32(bytes, 20);
    if (width * height > static_cast<std::uint64_t>(kMaxDecodePixels)) return bytes.size();
    return png_alloc_limit(bytes.size(), width, height) + width * height * 3;
  }
  return 2 * bytes.size();  // a PPM holds every pixel it decodes to
}

std::optional<Image> decode_image(std::string_view bytes, std::string* error,
                                  long long max_pixels) {
  if (bytes.starts_with(kPngSignature)) return decode_png(bytes, error, max_pixels);
  if (bytes.size() >= 2 && bytes[0] == 'P' && (bytes[1] == '3' || bytes[1] == '6')) {
    return decode_ppm(bytes, error, max_pixels);
  }
  if (bytes.size() >= 2 && bytes[0] == 'P' && bytes[1] >= '1' && bytes[1] <= '7') {
    return fail(error, "unsupported Netpbm type P" + std::string(1, bytes[1]) +
                           ": only PPM (P3, P6) is read");
  }
  return fail(error, "not a PNG or PPM image");
}

}  // namespace rayfarm
