// Render options (SPEC §4): one table of names, parsed the same way from the JSON "render"
// object, HTTP query parameters and command-line flags.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rayfarm/diagnostic.h"

namespace rayfarm {

enum class Highlight { phong, blinn };
enum class Precision { f64, f32 };
enum class ImageFormat { png, ppm };
enum class Profile { lecture, cpsc102 };
enum class Rounding { nearest, truncate };

struct RenderOptions {
  int spp = 1;
  int max_depth = 8;
  double max_dist = std::numeric_limits<double>::infinity();
  bool shadows = true;
  Highlight highlight = Highlight::phong;
  double bailout = 0;
  Precision precision = Precision::f64;
  std::array<double, 3> background{0, 0, 0};
  int width = 0;   // 0: the camera's pixeldim
  int height = 0;
  std::string camera;  // empty: the first camera
  std::uint64_t seed = 0;
  ImageFormat format = ImageFormat::png;
  double target_error = 0;  // stop sampling once the error estimate (8-bit levels) is below; 0 = off
  double time_limit = 0;    // seconds; stop sampling when out of time; 0 = off
  bool specialize = true;   // run only the pipeline parts the scene needs (off: for testing)
  Profile profile = Profile::lecture;
  std::optional<Rounding> rounding;

  Rounding effective_rounding() const {
    return rounding ? *rounding : profile == Profile::cpsc102 ? Rounding::truncate : Rounding::nearest;
  }
  double effective_max_dist() const { return profile == Profile::cpsc102 && std::isinf(max_dist) ? 20.0 : max_dist; }
  int effective_max_depth() const { return profile == Profile::cpsc102 ? 64 : max_depth; }

  bool operator==(const RenderOptions&) const = default;
};

struct OptionSpec {
  std::string_view name;
  std::string_view value_help;  // e.g. "1..N"
  std::string_view help;
};

std::span<const OptionSpec> option_specs();
const OptionSpec* find_option(std::string_view name);

// One assignment as written, with where it was written.
struct OptionValue {
  std::string name;
  std::string value;
  Where where;

  bool operator==(const OptionValue&) const = default;
};
using OptionSet = std::vector<OptionValue>;

// Applies `name=value`; returns an error message (naming the accepted values) on failure.
std::optional<std::string> apply_option(RenderOptions& options, std::string_view name,
                                        std::string_view value);
// Applies every assignment in order; reports each failure with its place.
void apply_options(RenderOptions& options, const OptionSet& set, Diagnostics& diags);

// The options that change the rendered pixels, as a stable string (cache keys, reports).
std::string canonical_string(const RenderOptions& options);
// All options as `name=value` pairs in table order (JSON status, summaries).
std::vector<std::pair<std::string, std::string>> option_pairs(const RenderOptions& options);

std::string_view to_string(Precision p);
std::string_view to_string(Highlight h);
std::string_view to_string(ImageFormat f);
std::string format_number(double v);  // shortest text that reads back to the same double

}  // namespace rayfarm
