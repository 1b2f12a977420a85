// The job routes: GET and DELETE /jobs/ID, GET /jobs/ID/image, the event stream of
// GET /jobs/ID/events, and GET /jobs (the caller's own jobs).
#include <chrono>
#include <cstdint>
#include <memory>
#include <thread>

#include "http_util.h"
#include "routes.h"

namespace rayfarm::server {
namespace {

using httplib::Request;
using httplib::Response;
using Json = nlohmann::json;
using Clock = std::chrono::steady_clock;

struct StreamState {
  explicit StreamState(Slot s) : slot(std::move(s)) {}
  Slot slot;  // held while the stream is open
  std::string id;
  std::uint64_t sent_version = 0;  // none sent yet: a record's version is at least 1
  nlohmann::json sent_position;    // the queue position last sent: it moves without a version
  Clock::time_point last_sent{};
};

// One event (or a keep-alive comment) of GET /jobs/ID/events; false ends the stream.
bool send_next_event(Service& svc, StreamState& state, httplib::DataSink& sink) {
  // At most ten events a second, at least four while the job changes.
  std::this_thread::sleep_until(state.last_sent + std::chrono::milliseconds(100));
  auto job = svc.await(state.slot, state.id, state.sent_version,
                       Clock::now() + std::chrono::milliseconds(250));
  if (!job || !sink.is_writable()) return false;  // expired meanwhile, or the client left
  const std::uint64_t version = job->version;
  const JobState js = job->state;
  if (svc.stopped() && !is_final(js)) {
    std::string msg = "event: shutdown\ndata: {}\n\n";
    sink.write(msg.data(), msg.size());
    sink.done();
    return true;
  }
  std::string event;
  const nlohmann::json status = svc.status(*job);
  const nlohmann::json position = status.value("queue_position", nlohmann::json());
  if (is_final(js)) {
    event = "event: " + std::string(to_string(js)) + "\ndata: " + json_text(status) + "\n\n";
  } else if (version != state.sent_version || position != state.sent_position) {
    event = "event: progress\ndata: " + json_text(status) + "\n\n";
  } else {
    event = ": waiting\n\n";  // keeps proxies open and finds departed clients
  }
  state.sent_version = version;
  state.sent_position = position;
  state.last_sent = Clock::now();
  if (!sink.write(event.data(), event.size())) return false;
  if (is_final(js)) sink.done();
  return true;
}

}  // namespace

void get_job(Service& svc, const Request& req, Response& res) {
  if (!check_query(req, res, "GET /jobs/ID", {})) return;
  auto job = svc.find(req.matches[1]);
  if (!job) return send_error(res, 404, "not_found", "no job " + req.matches[1].str());
  send_json(res, 200, svc.status(*job));
}

void delete_job(Service& svc, const Request& req, Response& res) {
  if (!check_query(req, res, "DELETE /jobs/ID", {})) return;
  const std::string id = req.matches[1];
  ApiError e = svc.cancel(id, client_of(req));
  if (e) return send_error(res, e);
  auto job = svc.find(id);
  // A running job stops within a tile: answer with its state after the cancel, not before
  // (when a waiting slot is free; else at once, with the state as it is).
  const auto deadline = Clock::now() + std::chrono::seconds(2);
  if (auto slot = svc.take_slot(Slot::Kind::waiting))
    while (job && !is_final(job->state) && Clock::now() < deadline && !svc.stopped())
      job = svc.await(*slot, id, job->version, deadline);
  if (!job) return send_error(res, 404, "not_found", "no job " + id);
  send_json(res, 200, svc.status(*job));
}

void get_job_image(Service& svc, const Request& req, Response& res) {
  if (!check_query(req, res, "GET /jobs/ID/image",
                   {{"format", {"png", "ppm"}},
                    {"partial", {"1", "0", "true", "false", "yes", "no"}}}))
    return;
  auto job = svc.find(req.matches[1]);
  if (!job) return send_error(res, 404, "not_found", "no job " + req.matches[1].str());
  const JobState state = job->state;
  if (param_true(req, "partial") && state != JobState::done) {
    auto image = svc.current_image(*job);
    if (!image) return send_error(res, 410, "expired", "the result has expired");
    res.set_header("X-Job-State", std::string(to_string(state)));
    // The same address shows more of the image as tiles finish: no cache may keep one.
    res.set_header("Cache-Control", "no-store");
    return send_image(res, *image, wants_ppm(req, *job));
  }
  if (state == JobState::done) {
    if (!send_result(svc, req, res, *job))
      send_error(res, 410, "expired", "the result has expired");
    return;
  }
  if (state == JobState::canceled) return send_error(res, 410, "canceled", "the job was canceled");
  // Failed: final, so the job's own error, as a wait=1 render answers it (no Retry-After).
  if (state == JobState::failed) return send_error(res, failed_job_error(*job));
  // Not done yet: the documented error shape, with the status beside it to poll on.
  nlohmann::json body = svc.status(*job);
  body["error"] = {{"code", "not_done"},
                   {"message", "the job is " + std::string(to_string(state)) +
                                   "; its image is ready when the state is done"}};
  res.set_header("Retry-After", "1");
  send_json(res, 409, body);
}

void get_job_events(Service& svc, const Request& req, Response& res) {
  if (!check_query(req, res, "GET /jobs/ID/events", {})) return;
  auto job = svc.find(req.matches[1]);
  if (!job) return send_error(res, 404, "not_found", "no job " + req.matches[1].str());
  auto slot = svc.take_slot(Slot::Kind::stream);
  if (!slot) {
    ApiError e;
    e.status = 503;
    e.code = "too_many_streams";
    e.message = "too many open event streams; poll /jobs/ID instead";
    e.retry_after = 2;
    return send_error(res, e);
  }
  auto state = std::make_shared<StreamState>(std::move(*slot));
  state->id = job->id;
  res.set_header("Cache-Control", "no-cache");
  res.set_header("X-Accel-Buffering", "no");
  res.set_chunked_content_provider(
      "text/event-stream",
      [&svc, state](size_t, httplib::DataSink& sink) {
        // cpp-httplib calls providers outside its exception handling: nothing may escape.
        try {
          return send_next_event(svc, *state, sink);
        } catch (const std::exception&) {
          return false;
        }
      },
      // The stream's slot goes with the last copy of its state (cpp-httplib drops the
      // provider when the response ends).
      [state](bool) mutable { state.reset(); });
}

void get_jobs(Service& svc, const Request& req, Response& res) {
  if (!check_query(req, res, "GET /jobs", {})) return;
  Json list = Json::array();
  for (const JobRecord& job : svc.jobs_of(client_of(req), 100)) list.push_back(svc.status(job));
  send_json(res, 200, {{"jobs", list}});
}

}  // namespace rayfarm::server
