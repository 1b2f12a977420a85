// Fuzz targets for the scene front end.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "format/model_fast.h"
#include "rayfarm/image_io.h"
#include "rayfarm/json_scene.h"
#include "rayfarm/lint.h"
#include "rayfarm/load.h"
#include "rayfarm/schema.h"
#include "rayfarm/model_parser.h"
#include "rayfarm/render.h"
#include "rayfarm/writers.h"
#include "targets.h"

namespace rayfarm::fuzz {
namespace {

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz property violated: %s\n", what);
    std::abort();
  }
}

bool same_scene(const Scene& a, const Scene& b) {
  if (a.cameras.size() != b.cameras.size() || a.materials.size() != b.materials.size() ||
      a.lights.size() != b.lights.size() || a.objects.size() != b.objects.size())
    return false;
  for (size_t i = 0; i < a.objects.size(); ++i)
    if (!(a.objects[i].shape == b.objects[i].shape) ||
        a.objects[i].material != b.objects[i].material)
      return false;
  for (size_t i = 0; i < a.materials.size(); ++i)
    if (a.materials[i].ambient != b.materials[i].ambient ||
        a.materials[i].shininess != b.materials[i].shininess)
      return false;
  return true;
}

// A render small enough to run for every input.
void tiny_render(const Scene& scene) {
  RenderOptions o;
  Diagnostics ignored;
  apply_options(o, scene.render, ignored);
  o.width = 4;
  o.height = 3;
  o.spp = o.spp > 2 ? 2 : o.spp;
  o.max_depth = std::min(o.effective_max_depth(), 3);
  o.time_limit = 0;
  std::string error;
  Image img = render_image(scene, o, 1, nullptr, {}, nullptr, &error);
  check(!error.empty() || img.rgb.size() == 4 * 3 * 3, "render size");
}

}  // namespace

int model_parser(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  Diagnostics diags;
  SceneDesc desc = parse_model(text, diags);
  std::optional<Scene> scene;
  if (!diags.has_errors()) scene = build_scene(desc, diags);
  for (const Diagnostic& d : diags.items()) (void)format_diagnostic(d, "fuzz", text);
  check(diags.has_errors() || scene.has_value(), "no errors but no scene");
  if (detect_format(text) == SceneFormat::model) {
    // The course lint reads any bytes, rejected files too, and points inside the text.
    Diagnostics course;
    lint_course(text, course);
    for (const Diagnostic& d : course.items()) {
      check(d.where.line >= 1 && d.where.column >= 1, "course lint position");
      (void)format_diagnostic(d, "fuzz", text);
    }
    // The loader's fast path decides as the full parser does, to the source positions.
    const LoadedScene quick = load_scene(text, LoadDetail::scene);
    check(quick.scene.has_value() == scene.has_value(), "fast path and full parser disagree");
    check(!scene || *quick.scene == *scene, "fast path built another scene");
    const std::optional<Scene> halves = load_model_fast(text, 0);  // read in two parts
    // It declines only scenes with kinds it does not read (or, in two parts, none it reads).
    bool others = false;
    if (quick.scene) {
      for (const Object& o : quick.scene->objects) others = others || !entity_spec(o.kind).fast_path;
      for (const Light& l : quick.scene->lights) others = others || l.kind != LightKind::point;
      others = others || !quick.scene->textures.empty();
    }
    check(halves.has_value() == (quick.scene.has_value() && !others),
          "the two-part read decides otherwise");
    check(!halves || *halves == *quick.scene, "the two-part read built another scene");
  }
  if (!scene) return 0;
  Diagnostics lints;
  lint_scene(*scene, RenderOptions{}, lints);
  // Round trips: model -> model and model -> JSON give the same scene.
  for (const std::string& again : {write_model(desc), write_json(desc)}) {
    LoadedScene reloaded = load_scene(again);
    check(reloaded.scene.has_value(), "a written scene does not load");
    check(same_scene(*scene, *reloaded.scene), "round trip changed the scene");
  }
  if (scene->objects.size() < 64) tiny_render(*scene);
  return 0;
}

int json_scene(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  Diagnostics diags;
  SceneDesc desc = parse_json_scene(text, diags);
  std::optional<Scene> scene;
  if (!diags.has_errors()) scene = build_scene(desc, diags);
  check(diags.has_errors() || scene.has_value(), "no errors but no scene");
  if (!scene) return 0;
  (void)write_pov(*scene, RenderOptions{});
  if (scene->objects.size() < 64) tiny_render(*scene);
  return 0;
}

int image_decode(const std::uint8_t* data, std::size_t size) {
  std::string error;
  auto image = decode_image(std::string_view(reinterpret_cast<const char*>(data), size), &error);
  check(image.has_value() || !error.empty(), "a failed decode without a message");
  if (!image || image->width == 0) return 0;
  for (ImageFormat f : {ImageFormat::png, ImageFormat::ppm}) {
    auto bytes = encode_image(*image, f);
    auto again = decode_image(std::string_view(reinterpret_cast<const char*>(bytes.data()),
                                               bytes.size()), &error);
    check(again.has_value() && *again == *image, "an image changed in a round trip");
  }
  return 0;
}

}  // namespace rayfarm::fuzz
