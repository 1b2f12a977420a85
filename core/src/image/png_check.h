// What a PNG decoder that follows the format checks and stb_image does not: each critical
// chunk's CRC, the header's fields, the zlib stream's Adler-32, and palette indices within the
// palette. libpng refuses all of these; without the checks a damaged file decoded to
// whatever pixels the damage left, and a grade was given for them.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace rayfarm {

// The first problem found in `png` (which starts with the signature and an IHDR chunk whose
// size the caller has checked), in words, with the byte or pixel where it is; nullopt when
// none is. A file cut short, or data inflating past `max_inflated` bytes, is left to the
// decoder, which says so.
std::optional<std::string> png_integrity_problem(std::string_view png, std::size_t max_inflated);

}  // namespace rayfarm
