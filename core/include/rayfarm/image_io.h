// Encoding and decoding images: PNG (written with libdeflate as its compressor, read with
// stb_image) and binary PPM (P6; P3 is read too).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rayfarm/image.h"
#include "rayfarm/options.h"

namespace rayfarm {

// The encoders throw std::invalid_argument when `rgb` is not width*height*3 bytes long; PNG
// also for an empty image or one over 1 GiB of filtered rows (~350 Mpixel), which one IDAT
// chunk would not hold far below its 2 GiB limit.
std::vector<unsigned char> encode_png(const Image& image);
std::vector<unsigned char> encode_ppm(const Image& image);
std::vector<unsigned char> encode_image(const Image& image, ImageFormat format);

// Upper bound on pixels decode_image accepts, to keep hostile headers from allocating.
constexpr long long kMaxDecodePixels = 64LL * 1024 * 1024;

// Decodes PNG or PPM (told apart by their signatures). Images with alpha or grey are
// converted to RGB. On failure returns nullopt and sets `error`. An image of more than
// `max_pixels` (by its header, before anything is allocated) is refused: a server takes no
// more than it would render.
std::optional<Image> decode_image(std::string_view bytes, std::string* error,
                                  long long max_pixels = kMaxDecodePixels);

// About the most memory decode_image takes for these bytes, read from the header: a PNG of a
// few KB can decode to hundreds of MB, so a server admits decodes by this, not their size.
// (Over kMaxDecodePixels the decode is refused at its header: the bytes' size then.)
std::uint64_t decode_memory_bound(std::string_view bytes);

}  // namespace rayfarm
