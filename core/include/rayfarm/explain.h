// One pixel explained, and what every pixel of a render met: the path of each of a pixel's
// samples (ray, hits, every term of the shading equation with its numbers, the final bytes)
// as `rayfarm trace` prints it, and a per-pixel record (first object, reflection, shadow,
// highlight) that grading hints use to say where in a scene a student's image goes wrong.
// Both follow the profile's own tracer, so a pixel's explained bytes are its rendered bytes.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rayfarm/options.h"
#include "rayfarm/scene.h"

namespace rayfarm {

using Triple = std::array<double, 3>;

// What one light did for one hit.
struct LightTerm {
  int light = -1;
  std::string name;
  // "lit", "filtered" (reached through translucent objects), "shadowed", "faces_away" (the
  // light is behind the surface), "outside_cone" (spotlight), "off_slide" (projector),
  // "at_point" (the light sits on the point).
  std::string status;
  int blocker = -1;  // the object in the way, when shadowed; when filtered, the first filter
  std::string blocker_name, blocker_kind;
  double distance = 0;
  double n_dot_l = 0;
  Triple source{};      // the light's own emissivity
  bool slide = false;   // a projector: its slide may change what reaches the point
  Triple emissivity{};  // as it reaches the point (after distance, slide and filters)
  Triple diffuse{};     // the diffuse term added
  Triple specular{};    // the highlight term added
  // What is raised to the shininess: R·V (lecture, Phong), N·H (lecture, Blinn; cpsc102).
  double highlight_base = 0;
  // cpsc102: what the diffuse term is divided by (the distance, except behind a translucent
  // sphere, docs/profiles.md §6).
  double diffuse_distance = 0;
};

// One hit (or miss) along a sample's path.
struct PathHit {
  std::string ray;  // "primary", "reflected" or "transmitted"
  int parent = -1;  // index in PathTrace::hits of the hit this ray left; -1 for the primary
  int depth = 0;
  Triple origin{}, direction{};
  int object = -1;  // -1: the ray met nothing (or went past max_dist): background
  std::string object_name, kind, material;
  double t = 0;
  double travelled = 0;  // path length up to and including this hit
  Triple point{}, normal{};
  // The ambient colour at the point (material, tile or texel). The lecture adds
  // ambient/travelled; cpsc102 divides ambient plus the lights' terms by travelled.
  Triple ambient{};
  Triple diffuse_colour{};  // the diffuse colour at the point
  Triple specular{};        // the material's specular colour
  double shininess = 0;     // as the profile uses it (cpsc102: 0 is no highlight)
  std::vector<LightTerm> lights;
  Triple local{};       // this hit's own colour, before what its reflected/transmitted rays add
  Triple value{};       // the colour this ray returns
  bool capped = false;  // a miss because of max_dist: an object lies beyond it
  // The hits of this hit's reflected and transmitted rays (-1: none traced), and what they
  // add: value = local folded with keep · local + filter · transmitted, then
  // + weight · reflected (clamped in the lecture).
  int reflected = -1, transmitted = -1;
  Triple weight{}, filter{};
  double keep = 1;
};

struct PathTrace {
  Triple screen_point{};  // where the primary ray crosses the screen
  std::vector<PathHit> hits;
  Triple colour{};
};

struct PixelExplanation {
  int x = 0, y = 0;           // image coordinates, (0, 0) top left
  int width = 0, height = 0;  // of the image
  Profile profile = Profile::lecture;
  Precision precision = Precision::f64;    // the lecture's; cpsc102 has its own arithmetic
  Highlight highlight = Highlight::phong;  // the lecture's; cpsc102 has its own glint
  double max_dist = 0;                     // the path-length cap (infinite: none)
  std::string formula;  // the shading equation of the profile, in the notes' words
  std::vector<PathTrace> samples;
  Triple mean{};
  std::array<std::uint8_t, 3> bytes{};
  std::string rounding;  // "nearest" or "truncate"
};

// Samples past the first 64 keep their screen point and colour only, not their hits, and
// the text and JSON list the first 64 (the mean counts all): a pixel of a million samples
// is explained in bounded text and some 60 bytes a sample.
inline constexpr int kExplainedSamples = 64;

// Explains pixel (x, y) of `scene` rendered with `options`: all of its `spp` samples (a
// render stopped early by target_error or time_limit has fewer). nullopt with `error`
// when the render could not start or the pixel is outside the image.
std::optional<PixelExplanation> explain_pixel(const Scene& scene, const RenderOptions& options,
                                              int x, int y, std::string* error);

nlohmann::json explanation_json(const PixelExplanation& e);
std::string explanation_text(const PixelExplanation& e);

// What a pixel's first sample met (sample 0 with supersampling). A highlight term counts
// by its share of the pixel: in cpsc102 over travelled, and at a later hit times the
// reflection weights and filters on the way to it.
struct PixelRecord {
  enum Flag : std::uint8_t {
    hit = 1,           // the primary ray met an object
    reflection = 2,    // a reflected ray adds to the colour
    transmission = 4,  // a transmitted ray adds to the colour
    shadow = 8,        // a light that faces the first hit is blocked there
    highlight = 16,    // a highlight term of at least half a level at the first hit
    capped = 32,       // some ray of the path went past max_dist
    // The same at a later hit, one seen in a reflection or through a translucent object
    // (whose share of the pixel is not zero).
    later_shadow = 64,
    later_highlight = 128,
  };
  std::uint8_t flags = 0;
  // The first hit's largest highlight term, in 8-bit levels rounded up (at most 255): 0
  // only where it has none at all.
  std::uint8_t highlight_level = 0;
  std::int32_t object = -1;  // the first hit's object (index into scene.objects), -1 none
};

// The record of every pixel, rows top to bottom. nullopt with `error` when the render could
// not start. Runs on `threads` threads (0: all cores).
std::optional<std::vector<PixelRecord>> record_pixels(const Scene& scene,
                                                      const RenderOptions& options, int threads,
                                                      std::string* error);

// The scene prepared once (as a render prepares it) for any number of explanations and
// records: explain_pixel and record_pixels prepare it on every call. `scene` must outlive
// it. Const members may be called from several threads at once.
class Explainer {
 public:
  // nullptr with `error` when the render could not start.
  static std::unique_ptr<Explainer> create(const Scene& scene, const RenderOptions& options,
                                           std::string* error);
  ~Explainer();

  int width() const;
  int height() const;
  // As explain_pixel; nullopt with `error` when (x, y) is outside the image. `samples` > 0:
  // the first that many of the `spp` samples only, as a render stopped early by
  // target_error or time_limit takes them (its summary says spp N/M; lecture profile only:
  // cpsc102 takes every sample in one pass).
  std::optional<PixelExplanation> explain(int x, int y, std::string* error,
                                          int samples = 0) const;
  PixelRecord record(int x, int y) const;  // (x, y) must be in the image
  std::vector<PixelRecord> record_all(int threads) const;

  struct Backend;  // the profile's prepared pipeline (explain.cpp)

 private:
  Explainer(const Scene& scene, const RenderOptions& options, std::unique_ptr<Backend> backend);

  const Scene& scene_;
  const RenderOptions options_;
  std::unique_ptr<Backend> backend_;
};

}  // namespace rayfarm
