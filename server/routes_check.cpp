// POST /check: what `rayfarm check` says of a scene, without rendering it: every error and
// warning with its place, and with course=1 also where the course's reference program would
// stop on or misread it. A scene with errors is still a successful check (200, "ok": false).
#include "api_error.h"
#include "http_util.h"
#include "rayfarm/lint.h"
#include "rayfarm/load.h"
#include "routes.h"
#include "textures.h"

namespace rayfarm::server {

using httplib::Request;
using httplib::Response;

namespace {

nlohmann::json diagnostics_json(const Diagnostics& diags, Severity severity) {
  nlohmann::json out = nlohmann::json::array();
  for (const Diagnostic& d : diags.items())
    if (d.severity == severity) out.push_back(diagnostic_json(d));
  return out;
}

}  // namespace

void post_check(Service& svc, const Request& req, Response& res) {
  if (!check_query(req, res, "POST /check", {{"course", {"1", "0", "true", "false", "yes", "no"}}}))
    return;
  const bool course = param_true(req, "course");
  std::string text;
  TextureFiles textures;  // only their names are checked: a render refuses a part it does not name
  if (req.is_multipart_form_data()) {
    if (!req.has_file("scene"))
      return send_error(res, 400, "missing_scene", "multipart upload without a 'scene' part");
    if (req.files.count("scene") > 1)
      return send_error(res, 400, "duplicate_part", "part 'scene' is sent more than once");
    text = req.get_file_value("scene").content;
    if (ApiError e = texture_parts(req, {"scene"}, textures)) return send_error(res, e);
  } else {
    text = req.body;
  }
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    return send_error(res, 400, "empty_scene",
                      "the request has no scene: send a model file or a JSON scene as the body");

  // Textures are not read here (they are the render's to upload): a texture the scene names
  // is checked for its name, not its file.
  const LoadGate::Pass pass = svc.enter_load(text.size());
  LoadedScene loaded = load_scene(text);
  Diagnostics warnings;
  if (loaded.scene) {
    RenderOptions options;
    options.profile = svc.settings().default_profile;
    Diagnostics scratch;
    apply_options(options, loaded.scene->render, scratch);
    lint_scene(*loaded.scene, options, warnings);
  }
  for (const Diagnostic& d : loaded.diags.items())
    if (d.severity == Severity::warning) warnings.warning(d.code, d.message, d.where);
  const bool model = detect_format(text) == SceneFormat::model;
  if (course && model) lint_course(text, warnings);

  // The lints' one error (an image too large for any render) joins the loader's.
  nlohmann::json errors = diagnostics_json(loaded.diags, Severity::error);
  for (const nlohmann::json& e : diagnostics_json(warnings, Severity::error)) errors.push_back(e);
  if (loaded.scene)
    if (std::string unnamed = unnamed_part(*loaded.scene, textures); !unnamed.empty())
      errors.push_back({{"code", "unknown_part"}, {"message", unnamed}});
  nlohmann::json body = {{"ok", loaded.scene.has_value() && errors.empty()},
                         {"format", model ? "model" : "json"},
                         {"errors", std::move(errors)},
                         {"warnings", diagnostics_json(warnings, Severity::warning)}};
  // At most 50 errors are listed, as the command line shows them; it also says how many.
  if (loaded.diags.truncated()) {
    body["error_count"] = loaded.diags.error_count();
    if (!loaded.diags.counted_all()) body["error_count_is_a_lower_bound"] = true;
  }
  if (loaded.scene) {
    const Scene& s = *loaded.scene;
    nlohmann::json cameras = nlohmann::json::array();
    for (const Camera& c : s.cameras)
      cameras.push_back({{"name", c.name}, {"width", c.width}, {"height", c.height}});
    body["scene"] = {{"cameras", cameras},
                     {"materials", s.materials.size()},
                     {"lights", s.lights.size()},
                     {"objects", s.objects.size()}};
  }
  send_json(res, 200, body);
}

}  // namespace rayfarm::server
