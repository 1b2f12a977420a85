// Image comparison for graders: error metrics and a heat map of where two images differ.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "rayfarm/image.h"

namespace rayfarm {

struct CompareOptions {
  int threshold = 0;          // a channel difference above this makes a pixel differ (0..255)
  bool neighborhood = false;  // a pixel matches if any pixel of its 3x3 neighbourhood in the
                              // other image is within the threshold (forgives edge aliasing)
};

struct CompareResult {
  int width = 0;
  int height = 0;
  double rmse = 0;           // over all channels, in 8-bit levels
  double psnr = 0;           // dB; +infinity for identical images
  int max_abs = 0;           // largest channel difference
  double mean_abs = 0;       // mean channel difference
  long long differing_pixels = 0;
  double differing_fraction = 0;
  long long off_by_more_than_1 = 0;  // pixels with some channel more than 1 level off
  long long differing_channels = 0;  // channels not exactly equal, whatever the threshold
};

// nullopt (with `error`) when the sizes differ.
std::optional<CompareResult> compare_images(const Image& a, const Image& b,
                                            const CompareOptions& options, std::string* error);

// The metrics as the API and `rayfarm compare --json` give them (PSNR null when identical).
nlohmann::json compare_json(const CompareResult& result, const CompareOptions& options);

// Per-pixel heat map: black where equal, rising through blue/red/yellow with the largest
// channel difference; pixels over the threshold are never darker than a visible minimum.
// An empty image when the sizes differ.
Image diff_image(const Image& a, const Image& b, const CompareOptions& options);

}  // namespace rayfarm
