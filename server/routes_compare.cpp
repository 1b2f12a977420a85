// POST /compare: two uploaded images, or a scene (with its textures) rendered here against an
// uploaded image, compared pixel by pixel; the numbers as JSON or, with ?diff=1, the difference
// image.
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>

#include "http_util.h"
#include "rayfarm/compare.h"
#include "rayfarm/image_io.h"
#include "routes.h"

namespace rayfarm::server {

using httplib::Request;
using httplib::Response;
using Json = nlohmann::json;

void post_compare(Service& svc, const Request& req, Response& res) {
  if (!req.is_multipart_form_data())
    return send_error(res, 400, "bad_request",
                      "send multipart form data with parts 'a' and 'b', or 'scene' and 'image'");
  CompareOptions options;
  if (req.has_param("threshold")) {
    try {
      size_t used = 0;
      int t = std::stoi(req.get_param_value("threshold"), &used);
      if (used != req.get_param_value("threshold").size() || t < 0 || t > 255) throw 0;
      options.threshold = t;
    } catch (...) {
      return send_error(res, 400, "invalid_option", "threshold must be an integer in 0..255");
    }
  }
  options.neighborhood = param_true(req, "neighborhood");
  std::string error;
  std::optional<Image> a, b;
  std::string job_id;
  if (req.has_file("a") && req.has_file("b")) {
    a = decode_image(req.get_file_value("a").content, &error);
    if (!a) return send_error(res, 400, "invalid_image", "part 'a': " + error);
    b = decode_image(req.get_file_value("b").content, &error);
    if (!b) return send_error(res, 400, "invalid_image", "part 'b': " + error);
  } else if (req.has_file("scene") && req.has_file("image")) {
    b = decode_image(req.get_file_value("image").content, &error);
    if (!b) return send_error(res, 400, "invalid_image", "part 'image': " + error);
    Params params;
    for (auto& [k, v] : req.params)
      if (k != "threshold" && k != "neighborhood" && k != "diff") params.emplace_back(k, v);
    TextureFiles textures;
    if (ApiError e = texture_parts(req, {"scene", "image"}, textures)) return send_error(res, e);
    Submitted sub =
        svc.submit(req.get_file_value("scene").content, params, client_of(req), textures);
    if (sub.error) return send_error(res, sub.error);
    Job& job = *sub.job;
    job_id = job.id;
    std::unique_lock lock(job.mu);
    while (!is_final(job.state) && !svc.stopped())
      job.changed.wait_for(lock, std::chrono::milliseconds(500));
    bool done = job.state == JobState::done;
    std::string message = job.error;
    lock.unlock();
    if (!done)
      return send_error(res, 500, "render_failed",
                        "the reference render did not finish" + (message.empty() ? "" : ": " + message));
    a = svc.current_image(job);
    if (!a) return send_error(res, 410, "expired", "the reference image expired");
  } else {
    return send_error(res, 400, "bad_request",
                      "send parts 'a' and 'b' (two images), or 'scene' and 'image'");
  }
  auto result = compare_images(*a, *b, options, &error);
  if (!result) return send_error(res, 422, "size_mismatch", error);
  if (param_true(req, "diff")) return send_image(res, diff_image(*a, *b, options), false);
  Json body = compare_json(*result, options);
  if (!job_id.empty()) body["reference_job"] = job_id;
  send_json(res, 200, body);
}

}  // namespace rayfarm::server
