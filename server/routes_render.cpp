// POST /render: a scene from the body, a multipart 'scene' part (its textures in the other
// parts) or ?sample=NAME, queued, and with ?wait=1 answered with the result once the job ends.
#include <algorithm>
#include <fstream>
#include <set>

#include "connection.h"
#include "http_util.h"
#include "routes.h"

namespace rayfarm::server {
namespace {

using httplib::Request;
using httplib::Response;
using Json = nlohmann::json;

const std::set<std::string> kControlParams = {"wait", "sample"};

// An Idempotency-Key as Stripe takes them: 1 to 255 visible ASCII characters (a UUID is the
// usual choice).
ApiError check_idempotency_key(const Request& req, std::string& key) {
  if (!req.has_header("Idempotency-Key")) {
    // The library drops a header line with an empty value: read from the head as it came.
    if (GuardedServer::empty_header("Idempotency-Key"))
      return api_error(400, "invalid_idempotency_key",
                       "Idempotency-Key is empty: give 1 to 255 visible ASCII characters (a "
                       "UUID, say), or leave the header out");
    return {};
  }
  if (req.get_header_value_count("Idempotency-Key") > 1)
    return api_error(400, "invalid_idempotency_key", "Idempotency-Key is given more than once");
  key = req.get_header_value("Idempotency-Key");
  const bool visible = std::all_of(key.begin(), key.end(), [](char c) { return c > 0x20 && c < 0x7f; });
  if (key.empty() || key.size() > 255 || !visible)
    return api_error(400, "invalid_idempotency_key",
                     "Idempotency-Key must be 1 to 255 visible ASCII characters (a UUID, say)");
  return {};
}

// ?wait=1: holds the request until the job ends and answers with its result or error. False
// when it has not answered (no waiting slot free, or shutting down).
bool answer_when_final(Service& svc, const Request& req, Response& res, const JobRecord& submitted) {
  auto slot = svc.take_slot(Slot::Kind::waiting);
  if (!slot) {
    res.set_header("X-Wait", "unavailable");
    return false;
  }
  auto job = svc.await_final(*slot, submitted.id);
  if (!job) return false;  // expired meanwhile: the 202 says where it was
  const JobState state = job->state;
  if (state == JobState::done) {
    if (!send_result(svc, req, res, *job))
      send_error(res, 410, "expired", "the result has already expired");
    return true;
  }
  if (state == JobState::canceled) {
    send_error(res, 410, "canceled", "the job was canceled");
    return true;
  }
  if (state == JobState::failed) {
    send_error(res, failed_job_error(*job));
    return true;
  }
  // Shutting down: the job is persisted and the client can poll for it.
  return false;
}

}  // namespace

void post_render(Service& svc, const Request& req, Response& res) {
  if (!check_yes_no(req, res, "wait")) return;
  std::string text;
  TextureFiles textures;
  if (req.has_param("sample")) {
    if (!req.body.empty() || req.is_multipart_form_data())
      return send_error(res, 400, "bad_request",
                        "the request names a sample and also sends a body: send one or the other");
    const Sample* sample = svc.sample(req.get_param_value("sample"));
    if (!sample) {
      std::string names;
      for (const Sample& s : svc.samples()) names += (names.empty() ? "" : ", ") + s.name;
      return send_error(res, 404, "unknown_sample",
                        "no sample named '" + req.get_param_value("sample").substr(0, 64) +
                            "'; samples: " + names);
    }
    std::ifstream in(sample->path, std::ios::binary);
    text.assign(std::istreambuf_iterator<char>(in), {});
    textures = sample->textures;
  } else if (req.is_multipart_form_data()) {
    if (!req.has_file("scene"))
      return send_error(res, 400, "missing_scene", "multipart upload without a 'scene' part");
    if (req.files.count("scene") > 1)
      return send_error(res, 400, "duplicate_part", "part 'scene' is sent more than once");
    text = req.get_file_value("scene").content;
    if (ApiError e = texture_parts(req, {"scene"}, textures)) return send_error(res, e);
  } else {
    text = req.body;
  }
  SubmitHow how;
  if (ApiError e = check_idempotency_key(req, how.idempotency_key)) return send_error(res, e);
  // A client that waits for the answer is someone looking at the screen.
  if (param_true(req, "wait")) how.default_priority = Priority::interactive;
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    return send_error(res, 400, "empty_scene",
                      "the request has no scene: send a model file or a JSON scene as the body");
  Params params;
  for (auto& [k, v] : req.params) {
    // spp=4&spp=8: which one was meant? (The command line refuses a repeated flag too.)
    if (req.params.count(k) > 1) {
      ApiError e = api_error(400, "invalid_option", "'" + k.substr(0, 64) + "' is given more than once");
      e.path = k.substr(0, 64);
      return send_error(res, e);
    }
    if (!kControlParams.count(k)) params.emplace_back(k, v);
  }
  Submitted sub = svc.submit(text, params, client_of(req), textures, how);
  if (sub.error) {
    // `curl -d @scene.txt` strips the newlines: the first comment then swallows a model
    // file. (A JSON scene on one line is fine, and an option's error is not the scene's.)
    const std::size_t first = text.find_first_not_of(" \t\r");
    if (req.has_header(kFormEncodedMark) && sub.error.code == "invalid_scene" &&
        first != std::string::npos && text[first] != '{' &&
        text.find('\n') == std::string::npos && text.size() > 40)
      sub.error.message += " (the scene arrived as one line: curl -d removes newlines; send "
                           "the file with --data-binary @FILE)";
    return send_error(res, sub.error);
  }
  const JobRecord& submitted = *sub.job;
  if (sub.replayed) res.set_header("Idempotent-Replayed", "true");

  if (param_true(req, "wait") && answer_when_final(svc, req, res, submitted)) return;
  const JobRecord job = svc.find(submitted.id).value_or(submitted);  // a worker may have started it
  Json body = {{"id", job.id},
               {"state", to_string(job.state)},
               {"queue_position", svc.status(job)["queue_position"]},
               {"links",
                {{"self", "/jobs/" + job.id},
                 {"image", "/jobs/" + job.id + "/image"},
                 {"events", "/jobs/" + job.id + "/events"}}}};
  res.set_header("Location", "/jobs/" + job.id);
  send_json(res, 202, body);
}

}  // namespace rayfarm::server
