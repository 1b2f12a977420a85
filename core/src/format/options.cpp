// Render options: one table of descriptors (name, help, parse, print, whether it changes
// pixels) that parsing, printing, the CLI flags and the cache key all read.
#include "rayfarm/options.h"

#include <charconv>
#include <cmath>
#include <limits>

#include "rayfarm/model_parser.h"
#include "util/enum_table.h"

namespace rayfarm {
namespace {

constexpr int kMaxSpp = 1 << 20;
constexpr int kMaxDepthLimit = 100000;
constexpr int kMaxSide = 65535;
constexpr double kUnlimited = std::numeric_limits<double>::infinity();

constexpr EnumTable<Highlight, 2> kHighlights({{"phong", Highlight::phong},
                                               {"blinn", Highlight::blinn}});
constexpr EnumTable<Precision, 2> kPrecisions({{"double", Precision::f64},
                                               {"float", Precision::f32}});
constexpr EnumTable<ImageFormat, 2> kFormats({{"png", ImageFormat::png},
                                              {"ppm", ImageFormat::ppm}});
constexpr EnumTable<Profile, 2> kProfiles({{"lecture", Profile::lecture},
                                           {"cpsc102", Profile::cpsc102}});
constexpr EnumTable<Rounding, 2> kRoundings({{"nearest", Rounding::nearest},
                                             {"truncate", Rounding::truncate}});
constexpr EnumTable<Priority, 3> kPriorities({{"interactive", Priority::interactive},
                                              {"normal", Priority::normal},
                                              {"batch", Priority::batch}});

// What each profile means for the options a request leaves unset: the lecture's conventions,
// or the course program's MAX_DIST 20, 64 bounces and truncated bytes.
struct ProfileDefaults {
  int max_depth;
  double max_dist;
  Rounding rounding;
};

constexpr ProfileDefaults defaults_of(Profile p) {
  return p == Profile::cpsc102 ? ProfileDefaults{64, 20, Rounding::truncate}
                               : ProfileDefaults{8, kUnlimited, Rounding::nearest};
}

// A value as echoed in a message, shortened.
std::string shown(std::string_view v) {
  constexpr size_t kMax = 60;
  return v.size() > kMax ? std::string(v.substr(0, kMax)) + "..." : std::string(v);
}

std::optional<long long> parse_integer(std::string_view v) {
  long long out = 0;
  if (!v.empty() && v.front() == '+') v.remove_prefix(1);
  auto [ptr, ec] = std::from_chars(v.data(), v.data() + v.size(), out);
  if (ec != std::errc() || ptr != v.data() + v.size() || v.empty()) return std::nullopt;
  return out;
}

// `Out` is the field: a plain value, or an optional whose nullopt means "the profile's".
template <class Out>
std::optional<std::string> int_in(std::string_view v, long long lo, long long hi, Out& out) {
  auto n = parse_integer(v);
  if (!n || *n < lo || *n > hi)
    return "must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got '" +
           shown(v) + "'";
  out = static_cast<int>(*n);
  return std::nullopt;
}

template <class Out>
std::optional<std::string> number_at_least(std::string_view v, double lo, bool strict, Out& out) {
  std::string why;
  auto n = parse_number(v, &why);
  if (!n) return "'" + shown(v) + "' is not a number (" + why + ")";
  if (strict ? !(*n > lo) : !(*n >= lo))
    return std::string("must be ") + (strict ? "> " : ">= ") + format_number(lo) + ", got " +
           shown(v);
  out = *n + 0.0;  // -0 is 0: the same render, so the same cache key and ETag
  return std::nullopt;
}

std::optional<std::string> bool_in(std::string_view v, bool& out) {
  if (v == "true" || v == "1" || v == "yes" || v == "on")
    out = true;
  else if (v == "false" || v == "0" || v == "no" || v == "off")
    out = false;
  else
    return "must be true or false, got '" + shown(v) + "'";
  return std::nullopt;
}

template <class T, size_t N, class Out>
std::optional<std::string> enum_in(const EnumTable<T, N>& table, std::string_view v, Out& out) {
  auto e = table.parse(v);
  if (!e) return "must be " + table.accepted() + ", got '" + shown(v) + "'";
  out = *e;
  return std::nullopt;
}

std::optional<std::string> seed_in(std::string_view v, std::uint64_t& out) {
  auto [ptr, ec] = std::from_chars(v.data(), v.data() + v.size(), out);
  if (ec != std::errc() || ptr != v.data() + v.size() || v.empty())
    return "must be an integer in 0..18446744073709551615, got '" + shown(v) + "'";
  return std::nullopt;
}

// "r,g,b", "r g b" or one grey value.
std::optional<std::string> colour_in(std::string_view v, std::array<double, 3>& out) {
  std::vector<double> parts;
  size_t i = 0;
  while (i < v.size() && parts.size() <= 3) {
    while (i < v.size() && (v[i] == ',' || v[i] == ' ')) ++i;
    size_t j = i;
    while (j < v.size() && v[j] != ',' && v[j] != ' ') ++j;
    if (j > i) {
      double c = 0;
      if (auto err = number_at_least(v.substr(i, j - i), 0, false, c)) return err;
      parts.push_back(c);
    }
    i = j;
  }
  if (parts.size() == 1) parts.assign(3, parts[0]);
  if (parts.size() != 3) return "must be 3 numbers in 0..1 (R,G,B) or one grey value";
  // A colour above 1 would be clamped to white without a word; 255 is the usual slip.
  for (double c : parts)
    if (c > 1)
      return "must be at most 1, got " + format_number(c) + " (colours are 0..1, not 0..255)";
  out = {parts[0], parts[1], parts[2]};
  return std::nullopt;
}

std::string bool_text(bool b) { return b ? "true" : "false"; }

using Opts = RenderOptions;
using Text = std::string_view;

constexpr OptionSpec kOptions[] = {
    {"spp", "1..N", "samples per pixel (stratified jitter; 1 = the exact pixel point)",
     [](Opts& o, Text v) { return int_in(v, 1, kMaxSpp, o.spp); },
     [](const Opts& o) { return std::to_string(o.spp); }, true, "4"},
    {"max_depth", "0..N", "reflection bounces (default: the profile's)",
     [](Opts& o, Text v) { return int_in(v, 0, kMaxDepthLimit, o.max_depth); },
     [](const Opts& o) { return std::to_string(o.effective_max_depth()); }, true, "3"},
    {"max_dist", ">0|unlimited", "path-length cap (the lecture's MAX_DIST; default: the profile's)",
     [](Opts& o, Text v) -> std::optional<std::string> {
       if (v == "inf" || v == "unlimited") {
         o.max_dist = kUnlimited;
         return std::nullopt;
       }
       return number_at_least(v, 0, true, o.max_dist);
     },
     [](const Opts& o) {
       double d = o.effective_max_dist();
       return std::isinf(d) ? std::string("unlimited") : format_number(d);
     },
     true, "12.5"},
    {"shadows", "true|false", "cast shadow rays",
     [](Opts& o, Text v) { return bool_in(v, o.shadows); },
     [](const Opts& o) { return bool_text(o.shadows); }, true, "false"},
    {"highlight", kHighlights.value_help(), "specular highlight model",
     [](Opts& o, Text v) { return enum_in(kHighlights, v, o.highlight); },
     [](const Opts& o) { return std::string(to_string(o.highlight)); }, true, "blinn"},
    {"bailout", ">=0", "skip a reflection whose weight is below this",
     [](Opts& o, Text v) { return number_at_least(v, 0, false, o.bailout); },
     [](const Opts& o) { return format_number(o.bailout); }, true, "0.01"},
    {"precision", kPrecisions.value_help(), "arithmetic of the tracer",
     [](Opts& o, Text v) { return enum_in(kPrecisions, v, o.precision); },
     [](const Opts& o) { return std::string(to_string(o.precision)); }, true, "float"},
    {"background", "R,G,B", "colour of rays that hit nothing, each 0..1 (one number: grey)",
     [](Opts& o, Text v) { return colour_in(v, o.background); },
     [](const Opts& o) {
       const auto& c = o.background;
       return format_number(c[0]) + "," + format_number(c[1]) + "," + format_number(c[2]);
     },
     true, "0.5"},
    // 0 (and an empty camera) is what the defaults print, so a job record reads back.
    {"width", "0..65535", "image width (same world window; 0: the camera's pixeldim)",
     [](Opts& o, Text v) { return int_in(v, 0, kMaxSide, o.width); },
     [](const Opts& o) { return std::to_string(o.width); }, true, "7"},
    {"height", "0..65535", "image height (same world window; 0: the camera's pixeldim)",
     [](Opts& o, Text v) { return int_in(v, 0, kMaxSide, o.height); },
     [](const Opts& o) { return std::to_string(o.height); }, true, "5"},
    {"camera", "NAME", "which camera (default: the first)",
     [](Opts& o, Text v) -> std::optional<std::string> {
       if (v.size() > 256) return "must be a camera name";
       o.camera = std::string(v);
       return std::nullopt;
     },
     [](const Opts& o) { return o.camera; }, true, "side"},
    {"seed", "0..2^64-1", "jitter stream seed", [](Opts& o, Text v) { return seed_in(v, o.seed); },
     [](const Opts& o) { return std::to_string(o.seed); }, true, "7"},
    // The same pixels in another encoding.
    {"format", kFormats.value_help(), "output encoding",
     [](Opts& o, Text v) { return enum_in(kFormats, v, o.format); },
     [](const Opts& o) { return std::string(to_string(o.format)); }, false, "ppm"},
    {"profile", kProfiles.value_help(),
     "shading conventions: the lecture notes', or the course's reference program's",
     [](Opts& o, Text v) { return enum_in(kProfiles, v, o.profile); },
     [](const Opts& o) { return std::string(to_string(o.profile)); }, true, "cpsc102"},
    {"rounding", kRoundings.value_help(), "colour to byte (default: the profile's)",
     [](Opts& o, Text v) { return enum_in(kRoundings, v, o.rounding); },
     [](const Opts& o) { return std::string(to_string(o.effective_rounding())); }, true,
     "truncate"},
    // Both stop sampling early, so both change the pixels. A stop on the error estimate is
    // deterministic and cached; a time limit's depends on the machine, and the server does
    // not cache those, but the key still keeps them apart from full renders.
    {"target_error", ">=0", "stop sampling once the error estimate (8-bit levels) is below",
     [](Opts& o, Text v) { return number_at_least(v, 0, false, o.target_error); },
     [](const Opts& o) { return format_number(o.target_error); }, true, "0.5"},
    {"time_limit", ">=0", "seconds; stop sampling when out of time",
     [](Opts& o, Text v) { return number_at_least(v, 0, false, o.time_limit); },
     [](const Opts& o) { return format_number(o.time_limit); }, true, "2"},
    // Specialization never changes a byte (tests compare both paths).
    {"specialize", "true|false", "run only the pipeline parts the scene needs (false: testing)",
     [](Opts& o, Text v) { return bool_in(v, o.specialize); },
     [](const Opts& o) { return bool_text(o.specialize); }, false, "false"},
    // Which jobs a busy server starts first: when, never what.
    {"priority", kPriorities.value_help(),
     "queue class on a server: interactive, then normal, then batch (default: interactive with "
     "wait=1, else normal)",
     [](Opts& o, Text v) { return enum_in(kPriorities, v, o.priority); },
     [](const Opts& o) { return std::string(to_string(o.priority)); }, false, "batch"},
};

}  // namespace

int RenderOptions::effective_max_depth() const {
  return max_depth.value_or(defaults_of(profile).max_depth);
}
double RenderOptions::effective_max_dist() const {
  return max_dist.value_or(defaults_of(profile).max_dist);
}
Rounding RenderOptions::effective_rounding() const {
  return rounding.value_or(defaults_of(profile).rounding);
}

std::span<const OptionSpec> option_specs() { return kOptions; }

const OptionSpec* find_option(std::string_view name) {
  for (const OptionSpec& o : kOptions)
    if (o.name == name) return &o;
  return nullptr;
}

std::optional<std::string> apply_option(RenderOptions& options, std::string_view name,
                                        std::string_view value) {
  const OptionSpec* spec = find_option(name);
  if (!spec) return "unknown option '" + shown(name) + "'";
  return spec->parse(options, value);
}

void apply_options(RenderOptions& options, const OptionSet& set, Diagnostics& diags) {
  for (const OptionValue& v : set) {
    if (!find_option(v.name)) {
      std::vector<std::string_view> names;
      for (const OptionSpec& s : kOptions) names.push_back(s.name);
      std::string hint = nearest_word(v.name, names);
      diags.error("unknown-option",
                  "unknown render option '" + shown(v.name) + "'" +
                      (hint.empty() ? "" : " (did you mean '" + hint + "'?)"),
                  v.where);
      continue;
    }
    if (auto err = apply_option(options, v.name, v.value))
      diags.error("bad-option", "option " + v.name + " " + *err, v.where);
  }
}

std::string profile_conflict(const RenderOptions& o, std::string* option) {
  if (o.profile != Profile::cpsc102) return {};
  auto at = [option](const char* name, std::string message) {
    if (option) *option = name;
    return message;
  };
  if (o.precision != Precision::f64)
    return at("precision",
              "precision float is not available in the cpsc102 profile (it computes in the "
              "course program's own extended precision)");
  if (o.highlight != Highlight::phong)
    return at("highlight",
              "highlight blinn is not available in the cpsc102 profile (its glint is the course "
              "program's own)");
  if (o.bailout > 0) return at("bailout", "bailout is not available in the cpsc102 profile");
  // Its samples come in one pass, in the course program's order (its random() stream runs
  // through the pixels): there is no pass to stop after, so these limits could never act.
  if (o.time_limit > 0)
    return at("time_limit",
              "time_limit is not available in the cpsc102 profile (it takes every sample in "
              "one pass, in the course program's order; lower spp instead)");
  if (o.target_error > 0)
    return at("target_error",
              "target_error is not available in the cpsc102 profile (it takes every sample in "
              "one pass, in the course program's order; lower spp instead)");
  if (o.seed > 0xffffffffULL)
    return at("seed", "seed must be below 2^32 in the cpsc102 profile (it seeds glibc's random())");
  if (o.effective_max_depth() > kCpsc102MaxDepth)
    return at("max_depth", "the cpsc102 profile follows rays at most " +
                               std::to_string(kCpsc102MaxDepth) + " bounces deep; max_depth " +
                               std::to_string(o.effective_max_depth()) + " is more");
  return {};
}

std::string_view to_string(Precision p) { return kPrecisions.name(p); }
std::string_view to_string(Highlight h) { return kHighlights.name(h); }
std::string_view to_string(ImageFormat f) { return kFormats.name(f); }
std::string_view to_string(Profile p) { return kProfiles.name(p); }
std::string_view to_string(Rounding r) { return kRoundings.name(r); }
std::string_view to_string(Priority p) { return kPriorities.name(p); }

std::string format_number(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, ptr) : std::string("nan");
}

std::vector<std::pair<std::string, std::string>> option_pairs(const RenderOptions& options) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const OptionSpec& s : kOptions) out.emplace_back(s.name, s.print(options));
  return out;
}

std::string canonical_string(const RenderOptions& options) {
  std::string out;
  for (const OptionSpec& s : kOptions)
    if (s.affects_pixels) out += std::string(s.name) + "=" + s.print(options) + ";";
  return out;
}

}  // namespace rayfarm
