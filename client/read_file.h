// Reading a whole file or stream into memory, bounded: a scene, an image, a texture.
#pragma once

#include <cstdint>
#include <filesystem>
#include <istream>
#include <string>

namespace rayfarm::cli {

// The most the client reads from one file or stream: an end to a device or pipe that never
// ends (`rayfarm render /dev/zero` once filled memory until the program aborted), and some
// 13 million spheres of model file, or an image well past the decoder's 2^26 pixels in its
// usual forms (192 MiB as 8-bit binary PPM, 384 MiB at 16 bits).
inline constexpr std::uintmax_t kMaxInputBytes = std::uintmax_t{1} << 30;

// "larger than 1 GiB, the most rayfarm reads from one input"
std::string too_large(std::uintmax_t limit);

// Appends what is left of `in` to `text`: when `file` (the path `in` was opened on) is a
// regular file, its size first (one read; nothing at all when it is over the limit), then
// whatever follows (a file that grew, a pipe, a device). False when `text` would pass
// `limit` bytes in all; `text` then holds at most that many.
bool read_bounded(std::istream& in, const std::filesystem::path& file, std::uintmax_t limit,
                  std::string& text);

}  // namespace rayfarm::cli
