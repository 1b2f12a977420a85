// Scene lints.
#include "rayfarm/lint.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/geometric.hpp>

#include "rayfarm/options.h"
#include "rayfarm/render.h"
#include "rayfarm/schema.h"
#include "render/cpsc102/x87.h"

namespace rayfarm {
namespace {

std::string label(std::string_view kind, const std::string& name) {
  return std::string(kind) + (name.empty() ? "" : " '" + name + "'");
}

bool is_black(const glm::dvec3& c) { return c.x <= 0 && c.y <= 0 && c.z <= 0; }

}  // namespace

namespace {

// Where the scene's own render options ask for the size `options` has: the width, height or
// spp of its render block that is in effect (the last valid one of its name, as
// apply_options reads them) and gives the value used, unless that value is the default (a
// command line may have overridden it). Nowhere when none does.
Where render_block_place(const Scene& scene, const RenderOptions& options) {
  struct Size {
    const char* name;
    int RenderOptions::*field;
  };
  static constexpr Size kSizes[] = {{"width", &RenderOptions::width},
                                     {"height", &RenderOptions::height},
                                     {"spp", &RenderOptions::spp}};
  const RenderOptions defaults;
  for (const Size& size : kSizes)
    for (auto it = scene.render.rbegin(); it != scene.render.rend(); ++it) {
      if (it->name != size.name) continue;
      RenderOptions probe;
      if (apply_option(probe, it->name, it->value)) continue;  // refused: an earlier one holds
      const int used = options.*size.field;
      if (used > defaults.*size.field && probe.*size.field == used) return it->where;
      break;
    }
  return {};
}

// An error, not a warning: render refuses it. Its place is the camera's when the size is the
// camera's own, the render block's entry when the scene asks for it there.
void lint_size(const Scene& scene, const Camera& cam, const RenderOptions& options,
               Diagnostics& diags) {
  const bool sized_here = options.width <= 0 && options.height <= 0;
  if (std::string size = image_size_error(options.width > 0 ? options.width : cam.width,
                                          options.height > 0 ? options.height : cam.height,
                                          options.spp);
      !size.empty())
    diags.error("image-too-large",
                sized_here ? (cam.name.empty() ? "" : label("camera", cam.name) + ": ") + size +
                                 "; --width and --height render the same view smaller"
                           : "with the width and height asked for, " + size,
                sized_here ? cam.where : render_block_place(scene, options));
}

}  // namespace

void lint_image_size(const Scene& scene, const RenderOptions& options, Diagnostics& diags) {
  if (auto cam_index = scene.find_camera(options.camera))
    lint_size(scene, scene.cameras[*cam_index], options, diags);
}

namespace {

// The other cameras at their own sizes: each is rendered with --camera, and one too large for
// that is an error of the file, at that camera (a size the options give is said once, above).
void lint_other_cameras(const Scene& scene, const RenderOptions& options, Diagnostics& diags) {
  if (options.width > 0 || options.height > 0) return;
  const auto chosen = scene.find_camera(options.camera);
  for (std::size_t i = 0; i < scene.cameras.size(); ++i)
    if (!chosen || i != static_cast<std::size_t>(*chosen))
      lint_size(scene, scene.cameras[i], options, diags);
}

}  // namespace

// --precision float squares lengths (distances, discriminants): past about 1e18, or with a
// window under 1e-18 wide, those squares come within a factor of 100 of float's range (3.4e38
// down to 1.2e-38) and rays stop meeting anything. Measured on the lecture scene scaled: at
// 1e17 times its size float renders it as at 1, at 1e18 it loses parts, and at 1e-22 too.
void lint_float_range(const Scene& scene, const Camera& cam, const RenderOptions& options,
                      Diagnostics& diags) {
  if (options.precision != Precision::f32) return;
  constexpr double kLargest = 1e18, kSmallestWindow = 1e-18;
  double big = std::max({std::abs(cam.viewpoint.x), std::abs(cam.viewpoint.y),
                         std::abs(cam.viewpoint.z), cam.world_width, cam.world_height});
  Where where = cam.where;
  std::string what = label("camera", cam.name);
  auto consider = [&](double m, const Where& w, std::string_view kind, const std::string& name) {
    if (m > big) big = m, where = w, what = label(kind, name);
  };
  for (const Light& l : scene.lights) consider(largest_magnitude(l), l.where, "light", l.name);
  for (const Object& o : scene.objects)
    consider(largest_magnitude(o.shape), o.where, entity_spec(o.kind).keyword, o.name);
  const double window = std::min(cam.world_width, cam.world_height);
  auto text = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return std::string(buf);
  };
  if (big > kLargest)
    diags.warning("float-range",
                  what + " reaches " + text(big) +
                      ": with --precision float, lengths past 1e18 overflow when squared and "
                      "the image comes out wrong or black; render in double precision",
                  where);
  else if (window < kSmallestWindow)
    diags.warning("float-range",
                  "the window of " + label("camera", cam.name) + " is " + text(window) +
                      " wide: with --precision float, lengths under 1e-18 underflow when "
                      "squared and the image comes out wrong or black; render in double "
                      "precision",
                  cam.where);
}

// The course's program finds the plane of a triangle without one (and of a tri) as the unit
// of (v1 - v0) x (v2 - v1) in its own arithmetic: where the cross product's square overflows
// or vanishes (edges past about 1e77, or under about 1e-77) that is not a number, and the
// triangle is never drawn. The profile renders what the program did; this says so.
void lint_reference_triangles(const Scene& scene, const RenderOptions& options,
                              Diagnostics& diags) {
  if (options.profile != Profile::cpsc102) return;
  using cpsc102::V3;
  for (const Object& o : scene.objects) {
    const Triangle* t = o.as<Triangle>();
    if (!t || t->plane) continue;
    auto v3 = [](const glm::dvec3& v) { return V3{v.x, v.y, v.z}; };
    const V3 a = v3(t->vertex[0]), b = v3(t->vertex[1]), c = v3(t->vertex[2]);
    const V3 n = cpsc102::vertex_plane_normal(a, b, c);
    // Past the overflow the unit is 0 (times 1 / inf); past the underflow not a number, or
    // infinite where every component is tiny but not 0.
    if (const double d = cpsc102::dot(n, n); d > 0.5 && d < 2) continue;
    diags.warning("course-triangle-lost",
                  label(entity_spec(o.kind).keyword, o.name) +
                      ": the course's program cannot find its plane (the cross product of its "
                      "edges overflows or vanishes in its arithmetic), so the cpsc102 profile "
                      "draws nothing for it; scale the scene nearer to 1",
                  o.where);
  }
}

void lint_scene(const Scene& scene, const RenderOptions& options, Diagnostics& diags,
                bool every_camera) {
  auto cam_index = scene.find_camera(options.camera);
  if (!cam_index) {
    diags.warning("unknown-camera", "no camera named '" + options.camera + "'", {});
    return;
  }
  const Camera& cam = scene.cameras[*cam_index];
  lint_size(scene, cam, options, diags);
  if (every_camera) lint_other_cameras(scene, options, diags);
  lint_float_range(scene, cam, options, diags);
  lint_reference_triangles(scene, options, diags);
  glm::dvec3 eye = cam.viewpoint;
  glm::dvec3 centre{cam.world_width / 2, cam.world_height / 2, 0};
  glm::dvec3 view = centre - eye;
  bool has_view = glm::length(view) > 0;
  if (has_view) view = glm::normalize(view);

  for (const Light& l : scene.lights)
    for (const Object& o : scene.objects)
      if (const Sphere* s = o.as<Sphere>(); s && glm::length(l.location - s->center) < s->radius)
        if (scene.materials[o.material].transparency == 0)
          diags.warning("light-inside-sphere",
                        label("light", l.name) + " is inside " + label("sphere", o.name) +
                            ": it lights only that sphere's inside",
                        l.where);

  for (const Object& o : scene.objects) {
    const Sphere* s = o.as<Sphere>();
    if (!s) continue;
    if (glm::length(eye - s->center) < s->radius)
      diags.warning("eye-inside-sphere",
                    "the eye of " + label("camera", cam.name) + " is inside " +
                        label("sphere", o.name),
                    o.where);
    else if (has_view && glm::dot(s->center - eye, view) < -s->radius)
      diags.warning("behind-eye",
                    label("sphere", o.name) + " is behind the eye of " +
                        label("camera", cam.name) + " and cannot be seen directly",
                    o.where);
  }

  std::vector<bool> used(scene.materials.size(), false);
  for (const Object& o : scene.objects) {
    used[o.material] = true;
    if (const TiledPlane* t = o.as<TiledPlane>()) used[t->alt_material] = true;
  }
  for (size_t i = 0; i < scene.materials.size(); ++i)
    if (!used[i])
      diags.warning("unused-material",
                    "material '" + scene.materials[i].name + "' is never used",
                    scene.materials[i].where);

  bool lit = false;
  for (const Light& l : scene.lights) lit = lit || !is_black(l.emissivity);
  bool any_ambient = false;
  for (size_t i = 0; i < scene.materials.size(); ++i)
    if (used[i]) any_ambient = any_ambient || !is_black(scene.materials[i].ambient);
  bool objects = !scene.objects.empty();
  glm::dvec3 bg{options.background[0], options.background[1], options.background[2]};
  if (!objects && is_black(bg))
    diags.warning("black-image", "the scene has no objects: the image is all background", {});
  else if (objects && !lit && !any_ambient && is_black(bg))
    diags.warning("black-image",
                  scene.lights.empty()
                      ? "nothing is lit: there are no lights and no ambient colour, the image "
                        "is entirely black"
                      : "nothing is lit: every light has zero emissivity and no material has "
                        "ambient colour, the image is entirely black",
                  {});
}

}  // namespace rayfarm
