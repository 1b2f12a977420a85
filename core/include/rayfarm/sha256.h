// SHA-256 (FIPS 180-4) for content-addressed result keys and ETags: a cryptographic hash,
// so one user cannot craft a scene whose key collides with another user's.
#pragma once

#include <string>
#include <string_view>

namespace rayfarm {

std::string sha256_hex(std::string_view data);

}  // namespace rayfarm
