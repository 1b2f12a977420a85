// Fuzz targets, shared by the libFuzzer binaries and the regression test that replays every
// input a fuzzer ever found. Each returns 0; a violated property aborts.
#pragma once

#include <cstddef>
#include <cstdint>

namespace rayfarm::fuzz {

// Model-file parse + build + lint (and the course lint); a file that parses must survive model and JSON round trips.
int model_parser(const std::uint8_t* data, std::size_t size);
// JSON scene parse + validate + prepare + a tiny render.
int json_scene(const std::uint8_t* data, std::size_t size);
// PNG/PPM decoding (uploads to /compare); a decoded image survives PNG and PPM round trips.
int image_decode(const std::uint8_t* data, std::size_t size);
// Raw bytes as an HTTP request to an in-process rayfarmd: never a 500, never a hang.
int http_request(const std::uint8_t* data, std::size_t size);

}  // namespace rayfarm::fuzz
