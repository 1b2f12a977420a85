// Render options: the table, parsing of `name=value` text, canonical forms.
#include "rayfarm/options.h"

#include <charconv>
#include <cmath>
#include <cstring>

#include "rayfarm/model_parser.h"

namespace rayfarm {
namespace {

constexpr int kMaxSpp = 1 << 20;
constexpr int kMaxDepthLimit = 100000;
constexpr int kMaxSide = 65535;

constexpr OptionSpec kOptions[] = {
    {"spp", "1..N", "samples per pixel (stratified jitter; 1 = the exact pixel point)"},
    {"max_depth", "0..N", "reflection bounces"},
    {"max_dist", ">0", "path-length cap (the lecture's MAX_DIST); default unlimited"},
    {"shadows", "true|false", "cast shadow rays"},
    {"highlight", "phong|blinn", "specular highlight model"},
    {"bailout", ">=0", "skip a reflection whose weight is below this"},
    {"precision", "double|float", "arithmetic of the tracer"},
    {"background", "R,G,B", "colour of rays that hit nothing (one number: grey)"},
    {"width", "1..65535", "image width (same world window)"},
    {"height", "1..65535", "image height (same world window)"},
    {"camera", "NAME", "which camera (default: the first)"},
    {"seed", "0..2^64-1", "jitter stream seed"},
    {"format", "png|ppm", "output encoding"},
    {"target_error", ">=0", "stop sampling once the error estimate (8-bit levels) is below"},
    {"time_limit", ">=0", "seconds; stop sampling when out of time"},
    {"specialize", "true|false", "run only the pipeline parts the scene needs (false: testing)"},
    {"profile", "lecture|cpsc102", "TEMPORARY"},
};

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

std::optional<bool> parse_bool(std::string_view v) {
  if (v == "true" || v == "1" || v == "yes" || v == "on") return true;
  if (v == "false" || v == "0" || v == "no" || v == "off") return false;
  return std::nullopt;
}

std::optional<std::string> int_in(std::string_view v, long long lo, long long hi, int& out) {
  auto n = parse_integer(v);
  if (!n || *n < lo || *n > hi)
    return "must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got '" +
           shown(v) + "'";
  out = static_cast<int>(*n);
  return std::nullopt;
}

std::optional<std::string> number_at_least(std::string_view v, double lo, bool strict,
                                           double& out) {
  std::string why;
  auto n = parse_number(v, &why);
  if (!n) return "'" + shown(v) + "' is not a number (" + why + ")";
  if (strict ? !(*n > lo) : !(*n >= lo))
    return std::string("must be ") + (strict ? "> " : ">= ") + format_number(lo) + ", got " +
           shown(v);
  out = *n;
  return std::nullopt;
}

}  // namespace

std::span<const OptionSpec> option_specs() { return kOptions; }

const OptionSpec* find_option(std::string_view name) {
  for (const OptionSpec& o : kOptions)
    if (o.name == name) return &o;
  return nullptr;
}

std::optional<std::string> apply_option(RenderOptions& o, std::string_view name,
                                        std::string_view value) {
  if (name == "spp") return int_in(value, 1, kMaxSpp, o.spp);
  if (name == "max_depth") return int_in(value, 0, kMaxDepthLimit, o.max_depth);
  if (name == "width") return int_in(value, 1, kMaxSide, o.width);
  if (name == "height") return int_in(value, 1, kMaxSide, o.height);
  if (name == "max_dist") {
    if (value == "inf" || value == "unlimited") {
      o.max_dist = std::numeric_limits<double>::infinity();
      return std::nullopt;
    }
    return number_at_least(value, 0, true, o.max_dist);
  }
  if (name == "bailout") return number_at_least(value, 0, false, o.bailout);
  if (name == "target_error") return number_at_least(value, 0, false, o.target_error);
  if (name == "time_limit") return number_at_least(value, 0, false, o.time_limit);
  if (name == "shadows" || name == "specialize") {
    auto b = parse_bool(value);
    if (!b) return "must be true or false, got '" + shown(value) + "'";
    (name == "shadows" ? o.shadows : o.specialize) = *b;
    return std::nullopt;
  }
  if (name == "highlight") {
    if (value == "phong")
      o.highlight = Highlight::phong;
    else if (value == "blinn")
      o.highlight = Highlight::blinn;
    else
      return "must be phong or blinn, got '" + shown(value) + "'";
    return std::nullopt;
  }
  if (name == "precision") {
    if (value == "double")
      o.precision = Precision::f64;
    else if (value == "float")
      o.precision = Precision::f32;
    else
      return "must be double or float, got '" + shown(value) + "'";
    return std::nullopt;
  }
  if (name == "format") {
    if (value == "png")
      o.format = ImageFormat::png;
    else if (value == "ppm")
      o.format = ImageFormat::ppm;
    else
      return "must be png or ppm, got '" + shown(value) + "'";
    return std::nullopt;
  }
  if (name == "profile") {  // TEMPORARY until the options table lands
    if (value == "lecture") o.profile = Profile::lecture;
    else if (value == "cpsc102") o.profile = Profile::cpsc102;
    else return "must be lecture or cpsc102";
    return std::nullopt;
  }
  if (name == "camera") {
    if (value.empty() || value.size() > 256) return "must be a camera name";
    o.camera = std::string(value);
    return std::nullopt;
  }
  if (name == "seed") {
    std::uint64_t s = 0;
    auto [ptr, ec] = std::from_chars(value.data(), value.data() + value.size(), s);
    if (ec != std::errc() || ptr != value.data() + value.size() || value.empty())
      return "must be an integer in 0..18446744073709551615, got '" + shown(value) + "'";
    o.seed = s;
    return std::nullopt;
  }
  if (name == "background") {
    // "r,g,b", "r g b" or one grey value.
    std::vector<double> parts;
    size_t i = 0;
    while (i < value.size() && parts.size() <= 3) {
      while (i < value.size() && (value[i] == ',' || value[i] == ' ')) ++i;
      size_t j = i;
      while (j < value.size() && value[j] != ',' && value[j] != ' ') ++j;
      if (j > i) {
        double c = 0;
        if (auto err = number_at_least(value.substr(i, j - i), 0, false, c)) return err;
        parts.push_back(c);
      }
      i = j;
    }
    if (parts.size() == 1) parts.assign(3, parts[0]);
    if (parts.size() != 3) return "must be 3 numbers >= 0 (R,G,B) or one grey value";
    o.background = {parts[0], parts[1], parts[2]};
    return std::nullopt;
  }
  return "unknown option '" + shown(name) + "'";
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

std::string_view to_string(Precision p) { return p == Precision::f64 ? "double" : "float"; }
std::string_view to_string(Highlight h) { return h == Highlight::phong ? "phong" : "blinn"; }
std::string_view to_string(ImageFormat f) { return f == ImageFormat::png ? "png" : "ppm"; }

std::string format_number(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, ptr) : std::string("nan");
}

std::vector<std::pair<std::string, std::string>> option_pairs(const RenderOptions& o) {
  auto colour = [](const std::array<double, 3>& c) {
    return format_number(c[0]) + "," + format_number(c[1]) + "," + format_number(c[2]);
  };
  return {
      {"spp", std::to_string(o.spp)},
      {"max_depth", std::to_string(o.max_depth)},
      {"max_dist", std::isinf(o.max_dist) ? "unlimited" : format_number(o.max_dist)},
      {"shadows", o.shadows ? "true" : "false"},
      {"highlight", std::string(to_string(o.highlight))},
      {"bailout", format_number(o.bailout)},
      {"precision", std::string(to_string(o.precision))},
      {"background", colour(o.background)},
      {"width", std::to_string(o.width)},
      {"height", std::to_string(o.height)},
      {"camera", o.camera},
      {"seed", std::to_string(o.seed)},
      {"format", std::string(to_string(o.format))},
      {"target_error", format_number(o.target_error)},
      {"time_limit", format_number(o.time_limit)},
      {"specialize", o.specialize ? "true" : "false"},
      {"profile", o.profile == Profile::lecture ? "lecture" : "cpsc102"},
  };
}

std::string canonical_string(const RenderOptions& options) {
  std::string out;
  for (auto& [k, v] : option_pairs(options)) {
    // Specialization never changes a byte, so it does not split the cache.
    if (k == "specialize") continue;
    out += k + "=" + v + ";";
  }
  return out;
}

}  // namespace rayfarm
