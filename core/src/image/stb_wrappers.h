// A small wrapper over stb_image (PNG decoding), compiled in stb_impl.cpp, the only file that
// includes stb, so its macros and static state stay out of the rest of core.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace rayfarm::stb {

struct DecodedPng {
  int width = 0;
  int height = 0;
  std::vector<unsigned char> rgb;  // empty on failure
  std::string error;               // stb's reason on failure
};

// Decodes a PNG to 8-bit RGB (grey, palette, alpha and 16-bit converted). Any single allocation
// over `alloc_limit` bytes fails the decode: without that a small hostile file can make stb
// reserve gigabytes (a chunk length of 2 GiB, or a zlib stream inflating far past the image).
DecodedPng decode_png_rgb(const unsigned char* data, int size, std::size_t alloc_limit);

}  // namespace rayfarm::stb
