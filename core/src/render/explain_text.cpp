// A pixel's explanation as JSON and as the text a student reads: each hit of each sample
// with every term of the profile's equation and its numbers, then the mean and the bytes.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "rayfarm/explain.h"

namespace rayfarm {
namespace {

using nlohmann::json;

json light_json(const LightTerm& l) {
  return {{"light", l.light},
          {"name", l.name},
          {"status", l.status},
          {"blocker", l.blocker},
          {"blocker_name", l.blocker_name},
          {"blocker_kind", l.blocker_kind},
          {"distance", l.distance},
          {"n_dot_l", l.n_dot_l},
          {"source", l.source},
          {"slide", l.slide},
          {"emissivity", l.emissivity},
          {"diffuse", l.diffuse},
          {"specular", l.specular},
          {"highlight_base", l.highlight_base},
          {"diffuse_distance", l.diffuse_distance}};
}

json hit_json(const PathHit& h) {
  json lights = json::array();
  for (const LightTerm& l : h.lights) lights.push_back(light_json(l));
  return {{"ray", h.ray},
          {"parent", h.parent},
          {"depth", h.depth},
          {"origin", h.origin},
          {"direction", h.direction},
          {"object", h.object},
          {"object_name", h.object_name},
          {"kind", h.kind},
          {"material", h.material},
          {"capped", h.capped},
          {"t", h.t},
          {"travelled", h.travelled},
          {"point", h.point},
          {"normal", h.normal},
          {"ambient", h.ambient},
          {"diffuse_colour", h.diffuse_colour},
          {"specular", h.specular},
          {"shininess", h.shininess},
          {"lights", lights},
          {"local", h.local},
          {"reflected", h.reflected},
          {"transmitted", h.transmitted},
          {"weight", h.weight},
          {"filter", h.filter},
          {"keep", h.keep},
          {"value", h.value}};
}

// Numbers with six significant digits: enough to follow the arithmetic by hand.
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string tri(const Triple& c) {
  return "(" + num(c[0]) + ", " + num(c[1]) + ", " + num(c[2]) + ")";
}

Triple plus(const Triple& a, const Triple& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Triple times(const Triple& a, const Triple& b) { return {a[0] * b[0], a[1] * b[1], a[2] * b[2]}; }
Triple times(const Triple& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
bool nonzero(const Triple& c) { return c[0] != 0 || c[1] != 0 || c[2] != 0; }
bool near(const Triple& a, const Triple& b) {
  for (int i = 0; i < 3; ++i) {
    // Equal infinities are near (their difference is not a number); an infinity is near
    // nothing else (any finite difference is within 1e-9 of it).
    if (a[i] == b[i]) continue;
    if (std::isinf(a[i]) || std::isinf(b[i]) ||
        !(std::abs(a[i] - b[i]) <= 1e-9 * std::max(std::abs(a[i]), std::abs(b[i]))))
      return false;
  }
  return true;
}

std::string object_text(int object, const std::string& kind, const std::string& name) {
  return kind + (name.empty() ? "" : " '" + name + "'") + " (object " + std::to_string(object) +
         ")";
}

struct TextWriter {
  const PixelExplanation& e;
  std::string out;

  void line(int indent, const std::string& text) { out += std::string(indent, ' ') + text + "\n"; }

  void light(const PathHit& h, const LightTerm& l) {
    const bool cpsc = e.profile == Profile::cpsc102;
    std::string head =
        "light " + std::to_string(l.light) + (l.name.empty() ? "" : " '" + l.name + "'");
    if (l.status == "at_point") return line(5, head + ": sits on the point; adds nothing");
    if (l.status == "faces_away")
      return line(5, head + ": behind the surface (N·L = " + num(l.n_dot_l) + "); adds nothing");
    if (l.status == "outside_cone")
      return line(5, head + ": the point is outside its cone; adds nothing");
    if (l.status == "off_slide")
      return line(5, head + ": its light misses the slide towards the point; adds nothing");
    if (l.status == "shadowed")
      return line(5, head + ": shadowed by " +
                         object_text(l.blocker, l.blocker_kind, l.blocker_name) + " (distance " +
                         num(l.distance) + ", N·L = " + num(l.n_dot_l) + "); adds nothing");
    head += l.status == "filtered"
                ? ": lit through " + object_text(l.blocker, l.blocker_kind, l.blocker_name) +
                      (cpsc ? "" : " and any other filters")
                : ": lit";
    line(5, head + ", distance " + num(l.distance) + ", N·L = " + num(l.n_dot_l));
    const std::string glint = cpsc || e.highlight == Highlight::blinn ? "(N·H)" : "(R·V)";
    const std::string power = glint + "^" + num(h.shininess);
    // What a slide or filters did to the light, where they did anything. A plain light's value
    // differs from the quotient in double only by float's rounding or range: shown unlabelled.
    const Triple plain = cpsc ? l.source : times(l.source, 1 / l.distance);
    const std::string by = l.status == "filtered" ? " · filters" : l.slide ? " · slide" : "";
    const std::string reaching =
        near(plain, l.emissivity) ? "" : by + std::string(" = ") + tri(l.emissivity);
    if (cpsc) {
      if (!reaching.empty()) line(7, "E = " + tri(l.source) + reaching);
      line(7, "diffuse: diffuse · E · N·L / d = " + tri(h.diffuse_colour) + " · " +
                  tri(l.emissivity) + " · " + num(l.n_dot_l) + " / " + num(l.diffuse_distance) +
                  " = " + tri(l.diffuse));
      if (h.shininess != 0)
        line(7, "highlight: E · specular · " + power + " = " + tri(l.emissivity) + " · " +
                    tri(h.specular) + " · " + num(l.highlight_base) + "^" + num(h.shininess) +
                    " = " + tri(l.specular));
      return;
    }
    line(7, "E/r = " + tri(l.source) + "/" + num(l.distance) +
                (reaching.empty() ? " = " + tri(l.emissivity) : reaching));
    line(7, "diffuse: E/r · diffuse · N·L = " + tri(l.emissivity) + " · " + tri(h.diffuse_colour) +
                " · " + num(l.n_dot_l) + " = " + tri(l.diffuse));
    if (nonzero(h.specular))
      line(7, "highlight: E/r · specular · " + power + " = " + tri(l.emissivity) + " · " +
                  tri(h.specular) + " · " + num(l.highlight_base) + "^" + num(h.shininess) + " = " +
                  tri(l.specular));
  }

  void hit(const PathTrace& s, int index) {
    const PathHit& h = s.hits[static_cast<std::size_t>(index)];
    const bool cpsc = e.profile == Profile::cpsc102;
    std::string head = "#" + std::to_string(index) + " " + h.ray + " ray";
    if (h.parent >= 0) head += " from #" + std::to_string(h.parent);
    head += " (depth " + std::to_string(h.depth) + "): from " + tri(h.origin) + " along " +
            tri(h.direction);
    line(2, head);
    if (h.object < 0) {
      if (h.capped && cpsc)
        line(5, "not traced: the path so far (" + num(h.travelled) + ") is longer than max_dist " +
                    num(e.max_dist) + "; background " + tri(h.value));
      else if (h.capped)
        line(5, "nothing within max_dist " + num(e.max_dist) + " (the path so far is " +
                    num(h.travelled) + "; an object lies beyond): background " + tri(h.value));
      else
        line(5, "meets nothing: background " + tri(h.value));
      return;
    }
    line(5, "hits " + object_text(h.object, h.kind, h.object_name) + ", material '" + h.material +
                "', at t = " + num(h.t) + "; travelled " + num(h.travelled));
    line(5, "point " + tri(h.point) + ", normal " + tri(h.normal));
    Triple sum = cpsc ? h.ambient : times(h.ambient, 1 / h.travelled);
    if (cpsc)
      line(5, "ambient = " + tri(h.ambient));
    else
      line(5, "ambient/travelled = " + tri(h.ambient) + "/" + num(h.travelled) + " = " + tri(sum));
    for (const LightTerm& l : h.lights) {
      light(h, l);
      sum = plus(sum, plus(l.diffuse, l.specular));
    }
    if (h.lights.empty()) line(5, "(no light adds anything in this scene)");
    if (cpsc)
      line(5, "(ambient + Σ lights) / travelled = " + tri(sum) + " / " + num(h.travelled) + " = " +
                  tri(h.local));
    else
      line(5, "local = clamp01(ambient/travelled + Σ lights) = clamp01" + tri(sum) + " = " +
                  tri(h.local));
    Triple c = h.local;
    if (h.transmitted >= 0) {
      const Triple& through = s.hits[static_cast<std::size_t>(h.transmitted)].value;
      c = plus(times(c, h.keep), times(h.filter, through));
      line(5, "transmitted ray (#" + std::to_string(h.transmitted) +
                  ") adds: (1 − transparency) · c + filter · #" + std::to_string(h.transmitted) +
                  " = " + num(h.keep) + " · " + tri(h.local) + " + " + tri(h.filter) + " · " +
                  tri(through) + " = " + tri(c));
    }
    if (h.reflected >= 0) {
      const Triple& mirrored = s.hits[static_cast<std::size_t>(h.reflected)].value;
      const Triple before = c;
      c = plus(c, times(h.weight, mirrored));
      line(5, "reflected ray (#" + std::to_string(h.reflected) +
                  ") adds: " + (cpsc ? "c + specular · #" : "clamp01(c + specular · #") +
                  std::to_string(h.reflected) + (cpsc ? "" : ")") + " = " +
                  (cpsc ? "" : "clamp01(") + tri(before) + " + " + tri(h.weight) + " · " +
                  tri(mirrored) + (cpsc ? "" : ")") + " = " + tri(h.value));
    }
    if (h.reflected >= 0 || h.transmitted >= 0 || !near(h.value, h.local))
      line(5, "value of #" + std::to_string(index) + " = " + tri(h.value));
  }

  // One channel's byte, with the product shown to as many digits as it takes to see which
  // side of the rounding boundary it lies on.
  void byte(const char* channel, double c, std::uint8_t b) {
    const bool nearest = e.rounding == "nearest";
    const double clamped = c > 0 ? (c < 1 ? c : 1.0) : 0.0;
    std::string text = std::string(channel) + ": " + num(c);
    if (clamped != c || std::isnan(c)) text += " → clamped to " + num(clamped);
    // cpsc102 multiplies in extended precision, the lecture in double.
    const long double product = e.profile == Profile::cpsc102
                                    ? static_cast<long double>(clamped) * 255
                                    : static_cast<long double>(255 * clamped);
    char shown[64];
    for (int digits = 6; digits <= 21; ++digits) {
      std::snprintf(shown, sizeof shown, "%.*Lg", digits, product);
      const long double back = std::strtold(shown, nullptr);
      if ((nearest ? std::floor(back + 0.5L) : std::floor(back)) == b) break;
    }
    text += " × 255 = " + std::string(shown) + " → ";
    text += nearest ? "floor(" + std::string(shown) + " + 0.5) = " + std::to_string(b)
                    : std::to_string(b) + " (truncate)";
    line(2, text);
  }
};

}  // namespace

nlohmann::json explanation_json(const PixelExplanation& e) {
  json samples = json::array();
  for (const PathTrace& s : e.samples) {
    if (samples.size() == static_cast<std::size_t>(kExplainedSamples)) break;
    json hits = json::array();
    for (const PathHit& h : s.hits) hits.push_back(hit_json(h));
    samples.push_back({{"screen_point", s.screen_point}, {"hits", hits}, {"colour", s.colour}});
  }
  json out = {{"x", e.x},
              {"y", e.y},
              {"sample_count", e.samples.size()},  // "samples" lists the first 64
              {"width", e.width},
              {"height", e.height},
              {"profile", to_string(e.profile)},
              {"formula", e.formula},
              {"samples", samples},
              {"mean", e.mean},
              {"bytes", {e.bytes[0], e.bytes[1], e.bytes[2]}},
              {"rounding", e.rounding}};
  if (e.profile == Profile::lecture) {
    out["precision"] = to_string(e.precision);
    out["highlight"] = to_string(e.highlight);
  }
  out["max_dist"] = std::isinf(e.max_dist) ? json(nullptr) : json(e.max_dist);
  return out;
}

std::string explanation_text(const PixelExplanation& e) {
  TextWriter w{e, {}};
  const int n = static_cast<int>(e.samples.size());
  std::string head = "Pixel (" + std::to_string(e.x) + ", " + std::to_string(e.y) + ") of " +
                     std::to_string(e.width) + "x" + std::to_string(e.height) + ", profile " +
                     std::string(to_string(e.profile));
  if (e.profile == Profile::lecture)
    head += " (" + std::string(e.precision == Precision::f32 ? "float" : "double") + ")";
  head += ", " + std::to_string(n) + (n == 1 ? " sample" : " samples");
  w.line(0, head);
  w.line(0, "Each hit: " + e.formula + ".");
  for (int k = 0; k < std::min(n, kExplainedSamples); ++k) {
    const PathTrace& s = e.samples[static_cast<std::size_t>(k)];
    w.line(0, "");
    w.line(0, "Sample " + std::to_string(k + 1) + " of " + std::to_string(n) +
                  ": the primary ray crosses the screen at " + tri(s.screen_point));
    for (int i = 0; i < static_cast<int>(s.hits.size()); ++i) w.hit(s, i);
    w.line(2, "sample colour " + tri(s.colour));
  }
  if (n > kExplainedSamples) {
    w.line(0, "");
    w.line(0, "Samples " + std::to_string(kExplainedSamples + 1) + " to " + std::to_string(n) +
                  " are in the mean below, not listed.");
  }
  w.line(0, "");
  if (n == 1) {
    w.line(0, "Pixel colour " + tri(e.mean));
  } else {
    Triple sum{};
    for (const PathTrace& s : e.samples) sum = plus(sum, s.colour);
    w.line(0, "Mean of the " + std::to_string(n) + " samples, summed in order: " + tri(sum) +
                  " / " + std::to_string(n) + " = " + tri(e.mean));
  }
  w.line(0, std::string("Bytes (") +
                (e.rounding == "nearest" ? "round to nearest: floor(255 · c + 0.5)"
                                         : "truncate: (unsigned char)(255 · c)") +
                ", after clamping c to [0, 1]):");
  w.byte("R", e.mean[0], e.bytes[0]);
  w.byte("G", e.mean[1], e.bytes[1]);
  w.byte("B", e.mean[2], e.bytes[2]);
  return w.out;
}

}  // namespace rayfarm
