// Render options (docs/rendering.md#render-options): one table, parsed alike from the JSON
// "render" object, HTTP query parameters and command-line flags, and printed from the same
// table for job status, records and the cache key.
#pragma once

#include <array>
#include <cstdint>
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
// Shading conventions: the lecture notes', or the course's reference program's.
enum class Profile { lecture, cpsc102 };
// Colour to byte: floor(255c + 0.5), or (unsigned char)(255c).
enum class Rounding { nearest, truncate };
// A server's queue class: every interactive job starts before any normal one, and every normal
// one before any batch one. Never changes a pixel.
enum class Priority { interactive, normal, batch };

struct RenderOptions {
  int spp = 1;
  // nullopt: the profile's default (lecture: 8, unlimited, nearest; cpsc102: 64, 20, truncate).
  // Read them through the effective_ accessors.
  std::optional<int> max_depth;
  std::optional<double> max_dist;
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
  Profile profile = Profile::lecture;
  std::optional<Rounding> rounding;
  double target_error = 0;  // stop sampling once the error estimate (8-bit levels) is below; 0 = off
  double time_limit = 0;    // seconds; stop sampling when out of time; 0 = off
  bool specialize = true;   // run only the pipeline parts the scene needs (off: for testing)
  Priority priority = Priority::normal;  // a server's queue class (rayfarmd: wait=1 means interactive)

  int effective_max_depth() const;
  double effective_max_dist() const;
  Rounding effective_rounding() const;

  bool operator==(const RenderOptions&) const = default;
};

// One option: how it reads, prints and whether it can change a pixel.
struct OptionSpec {
  std::string_view name;
  std::string_view value_help;  // e.g. "1..N"
  std::string_view help;
  // Sets the option from text; an error message (naming the accepted values) on failure.
  std::optional<std::string> (*parse)(RenderOptions&, std::string_view value);
  // The effective value, as text `parse` reads back.
  std::string (*print)(const RenderOptions&);
  bool affects_pixels;       // part of the cache key
  std::string_view example;  // a valid value that is not the default (tests set each option)
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

// The deepest the cpsc102 profile follows rays: it recurses as the course's program did, and
// a render thread's stack holds this many levels with room to spare.
inline constexpr int kCpsc102MaxDepth = 1000;

// What the chosen profile cannot do with these options, once all are applied: the cpsc102
// profile computes as the course's program did, so it has no float precision, no Blinn
// switch (its glint is its own), no bailout, a 32-bit seed for its jitter stream, and at
// most kCpsc102MaxDepth bounces. Empty when the combination is fine; otherwise `option`
// (when given) names the option at fault.
std::string profile_conflict(const RenderOptions& options, std::string* option = nullptr);

// The options that change the rendered pixels, as a stable string (cache keys, reports).
// Effective values: a profile's default and the same value given explicitly share a key.
std::string canonical_string(const RenderOptions& options);
// All options as `name=value` pairs in table order, effective values (JSON status, records).
std::vector<std::pair<std::string, std::string>> option_pairs(const RenderOptions& options);

std::string_view to_string(Precision p);
std::string_view to_string(Highlight h);
std::string_view to_string(ImageFormat f);
std::string_view to_string(Profile p);
std::string_view to_string(Rounding r);
std::string_view to_string(Priority p);
std::string format_number(double v);  // shortest text that reads back to the same double

}  // namespace rayfarm
