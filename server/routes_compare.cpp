// POST /compare: two uploaded images, or a scene (with its textures) rendered here against an
// uploaded image, compared pixel by pixel; the numbers as JSON or, with diff=1, the difference
// image. Its options come from the query or from form fields, and unknown ones are refused.
#include <charconv>
#include <cmath>
#include <optional>
#include <set>

#include "http_util.h"
#include "rayfarm/compare.h"
#include "rayfarm/image_io.h"
#include "rayfarm/model_parser.h"
#include "routes.h"

namespace rayfarm::server {

using httplib::Request;
using httplib::Response;
using Json = nlohmann::json;

namespace {

const std::set<std::string> kCompareOptions = {"threshold", "neighborhood", "diff",
                                               "max_bad_fraction"};

// A switch: 1, true or yes; 0, false or no. Anything else is refused, not taken for off.
std::optional<bool> switch_value(const std::string& v) {
  if (v == "1" || v == "true" || v == "yes") return true;
  if (v == "0" || v == "false" || v == "no") return false;
  return std::nullopt;
}

ApiError invalid_option(const std::string& name, const std::string& message) {
  ApiError e = api_error(400, "invalid_option", message);
  e.path = name.substr(0, 64);
  return e;
}

}  // namespace

std::optional<Image> render_and_wait(Service& svc, const Slot& slot, const std::string& scene,
                                     const Params& params, const std::string& client,
                                     const TextureFiles& textures, const SubmitHow& how,
                                     ApiError& error, std::string* job_id) {
  Submitted sub = svc.submit(scene, params, client, textures, how);
  if (sub.error) {
    error = sub.error;
    return std::nullopt;
  }
  if (job_id) *job_id = sub.job->id;
  auto job = svc.await_final(slot, sub.job->id);
  const bool done = job && job->state == JobState::done;
  const std::string message = job ? job->error : "";
  if (!done) {
    error = api_error(500, "render_failed",
                      "the reference render did not finish" + (message.empty() ? "" : ": " + message));
    return std::nullopt;
  }
  std::optional<Image> image = svc.current_image(*job);
  if (!image) error = api_error(410, "expired", "the reference image expired");
  return image;
}

std::map<std::string, std::string> request_fields(const Request& req,
                                                  const std::set<std::string>& names,
                                                  std::string* repeated) {
  std::map<std::string, std::string> out;
  auto add = [&](const std::string& k, const std::string& v) {
    if (!out.emplace(k, v).second && repeated && repeated->empty()) *repeated = k;
  };
  for (const auto& [k, v] : req.params) add(k, v);
  for (const auto& [name, part] : req.files)
    if (part.filename.empty() && names.count(name)) add(name, part.content);
  return out;
}

void post_compare(Service& svc, const Request& req, Response& res) {
  if (!req.is_multipart_form_data())
    return send_error(res, 400, "bad_request",
                      "send multipart form data with parts 'a' and 'b', or 'scene' and 'image'");
  const bool with_scene = req.has_file("scene") && req.has_file("image");
  // Form fields that name an option are options; with a scene, other parts are its textures.
  std::set<std::string> known = kCompareOptions;
  for (const OptionSpec& spec : option_specs()) known.insert(std::string(spec.name));
  std::string repeated;
  const std::map<std::string, std::string> fields = request_fields(req, known, &repeated);
  if (!repeated.empty())
    return send_error(res, invalid_option(repeated, "'" + repeated.substr(0, 64) +
                                                        "' is given more than once; give it once"));
  for (const char* part : {"a", "b", "scene", "image"})
    if (req.files.count(part) > 1)
      return send_error(res, 400, "duplicate_part",
                        std::string("part '") + part + "' is sent more than once");
  CompareOptions options;
  double max_bad_fraction = 0;
  bool diff = false;
  Params render_params;
  for (const auto& [k, v] : fields) {
    if (k == "threshold") {
      // As the render options read integers: digits after an optional '+', nothing around.
      std::string_view digits(v);
      if (digits.starts_with('+')) digits.remove_prefix(1);
      int t = -1;
      const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), t);
      if (digits.empty() || ec != std::errc() || end != digits.data() + digits.size() || t < 0 ||
          t > 255)
        return send_error(res, invalid_option(k, "threshold must be an integer in 0..255, got '" +
                                                     v.substr(0, 40) + "'"));
      options.threshold = t;
    } else if (k == "neighborhood" || k == "diff") {
      const std::optional<bool> on = switch_value(v);
      if (!on)
        return send_error(res, invalid_option(k, k + " must be 1, true or yes, or 0, false or no; got '" +
                                                     v.substr(0, 40) + "'"));
      (k == "diff" ? diff : options.neighborhood) = *on;
    } else if (k == "max_bad_fraction") {
      // Read as a scene's numbers are, and as the command line reads the same option (no
      // hexadecimal, a subnormal taken).
      const std::optional<double> f = parse_number(v);
      if (!f || !(*f >= 0 && *f <= 1))
        return send_error(res, invalid_option(k, "max_bad_fraction must be a number in 0..1"));
      max_bad_fraction = *f;
    } else if (with_scene && find_option(k)) {
      render_params.emplace_back(k, v);
    } else {
      ApiError e = api_error(400, "invalid_option",
                             "unknown option '" + k.substr(0, 64) +
                                 "': /compare takes threshold, neighborhood, max_bad_fraction and "
                                 "diff" + (with_scene ? ", and render options" : "; render options "
                                                                                  "need a scene"));
      e.path = k.substr(0, 64);
      return send_error(res, e);
    }
  }
  std::string error;
  std::optional<Image> a, b;
  std::string job_id;
  // No larger than the server would render: an image is decoded whole, three bytes a pixel.
  const long long max_pixels = svc.settings().max_pixels;
  // A small PNG can decode to hundreds of MB: decodes are admitted by what they will take (held
  // through the comparison), as large scenes are, or 64 threads at once would exhaust the
  // machine.
  LoadGate::Pass pass;
  if (req.has_file("a") && req.has_file("b")) {
    for (const auto& [name, part] : req.files)
      if (name != "a" && name != "b" && !(part.filename.empty() && known.count(name)))
      {
        ApiError e = api_error(400, "invalid_option",
                               "unexpected part '" + name.substr(0, 64) + "' beside 'a' and 'b'");
        e.path = name.substr(0, 64);
        return send_error(res, e);
      }
    const std::string& a_bytes = req.get_file_value("a").content;
    const std::string& b_bytes = req.get_file_value("b").content;
    pass = svc.enter_load(decode_memory_bound(a_bytes) + decode_memory_bound(b_bytes));
    a = decode_image(a_bytes, &error, max_pixels);
    if (!a) return send_error(res, 400, "invalid_image", "part 'a': " + error);
    b = decode_image(b_bytes, &error, max_pixels);
    if (!b) return send_error(res, 400, "invalid_image", "part 'b': " + error);
  } else if (with_scene) {
    const std::string& image_bytes = req.get_file_value("image").content;
    pass = svc.enter_load(decode_memory_bound(image_bytes));
    b = decode_image(image_bytes, &error, max_pixels);
    // Not held through the render: the scene's own load may need a pass, and the render takes
    // long (the decoded image waits in one of the few waiting slots meanwhile).
    pass = LoadGate::Pass();
    if (!b) return send_error(res, 400, "invalid_image", "part 'image': " + error);
    TextureFiles textures;
    if (ApiError e = texture_parts(req, {"scene", "image"}, textures)) return send_error(res, e);
    for (const auto& [name, part] : req.files)
      if (part.filename.empty() && known.count(name)) textures.erase(name);
    // The render is waited for here: it takes one of the waiting slots, as ?wait=1 does.
    auto slot = svc.take_slot(Slot::Kind::waiting);
    if (!slot) {
      ApiError e = api_error(503, "busy", "too many requests are waiting for renders; try again");
      e.retry_after = 2;
      return send_error(res, e);
    }
    ApiError render_error;
    SubmitHow how;
    how.default_priority = Priority::interactive;  // someone waits for it
    a = render_and_wait(svc, *slot, req.get_file_value("scene").content, render_params,
                        client_of(req), textures, how, render_error, &job_id);
    if (!a) return send_error(res, render_error);
  } else {
    return send_error(res, 400, "bad_request",
                      "send parts 'a' and 'b' (two images), or 'scene' and 'image'");
  }
  auto result = compare_images(*a, *b, options, &error);
  if (!result) {
    if (with_scene && !(req.has_file("a") && req.has_file("b"))) {
      const std::string image_size = std::to_string(b->width) + "x" + std::to_string(b->height);
      error = "the scene renders at " + std::to_string(a->width) + "x" +
              std::to_string(a->height) + " but the image is " + image_size +
              ": add width=" + std::to_string(b->width) + "&height=" +
              std::to_string(b->height) + " to render the scene at the image's size";
    } else {
      error = "image sizes differ: a is " + std::to_string(a->width) + "x" +
              std::to_string(a->height) + ", b is " + std::to_string(b->width) + "x" +
              std::to_string(b->height);
    }
    return send_error(res, 422, "size_mismatch", error);
  }
  Json body = compare_json(*result, options);
  body["max_bad_fraction"] = max_bad_fraction;
  body["match"] = result->differing_fraction <= max_bad_fraction;
  if (!job_id.empty()) body["reference_job"] = job_id;
  if (diff) {
    // The heat map and its figures in one answer: a grader need not ask twice.
    for (const char* key : {"differing_pixels", "differing_fraction", "rmse", "psnr", "max_abs",
                            "identical", "match"}) {
      std::string name = "X-Compare-";
      for (const char* c = key; *c; ++c) name += *c == '_' ? '-' : *c;
      res.set_header(name.c_str(), body[key].dump());
    }
    if (!job_id.empty()) res.set_header("X-Job-Id", job_id);
    return send_image(res, diff_image(*a, *b, options), false);
  }
  send_json(res, 200, body);
}

}  // namespace rayfarm::server
