// The job routes: GET and DELETE /jobs/ID, GET /jobs/ID/image, the event stream of
// GET /jobs/ID/events, and GET /jobs (the caller's own jobs).
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
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
  std::uint64_t sent_version = ~0ULL;
  Clock::time_point last_sent{};
};

// One event (or a keep-alive comment) of GET /jobs/ID/events; false ends the stream.
bool send_next_event(Service& svc, const std::shared_ptr<Job>& job, StreamState& state,
                     httplib::DataSink& sink) {
  // At most ten events a second, at least four while the job changes.
  std::this_thread::sleep_until(state.last_sent + std::chrono::milliseconds(100));
  std::uint64_t version;
  JobState js;
  {
    std::unique_lock lock(job->mu);
    job->changed.wait_for(lock, std::chrono::milliseconds(250), [&] {
      return job->version != state.sent_version || is_final(job->state);
    });
    version = job->version;
    js = job->state;
  }
  if (!sink.is_writable()) return false;
  if (svc.stopped() && !is_final(js)) {
    std::string msg = "event: shutdown\ndata: {}\n\n";
    sink.write(msg.data(), msg.size());
    sink.done();
    return true;
  }
  std::string event;
  if (is_final(js)) {
    event = "event: " + std::string(to_string(js)) + "\ndata: " +
            json_text(svc.status(*job)) + "\n\n";
  } else if (version != state.sent_version) {
    event = "event: progress\ndata: " + json_text(svc.status(*job)) + "\n\n";
  } else {
    event = ": waiting\n\n";  // keeps proxies open and finds departed clients
  }
  state.sent_version = version;
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
  ApiError e = svc.cancel(req.matches[1], client_of(req));
  if (e) return send_error(res, e);
  auto job = svc.find(req.matches[1]);
  {
    // A running job stops within a tile: answer with its state after the cancel, not before.
    std::unique_lock lock(job->mu);
    job->changed.wait_for(lock, std::chrono::seconds(2), [&] { return is_final(job->state); });
  }
  send_json(res, 200, svc.status(*job));
}

void get_job_image(Service& svc, const Request& req, Response& res) {
  if (!check_query(req, res, "GET /jobs/ID/image",
                   {{"format", {"png", "ppm"}},
                    {"partial", {"1", "0", "true", "false", "yes", "no"}}}))
    return;
  auto job = svc.find(req.matches[1]);
  if (!job) return send_error(res, 404, "not_found", "no job " + req.matches[1].str());
  JobState state;
  {
    std::lock_guard lock(job->mu);
    state = job->state;
  }
  if (param_true(req, "partial") && state != JobState::done) {
    auto image = svc.current_image(*job);
    if (!image) return send_error(res, 410, "expired", "the result has expired");
    res.set_header("X-Job-State", std::string(to_string(state)));
    return send_image(res, *image, wants_ppm(req, *job));
  }
  if (state == JobState::done) {
    if (!send_result(svc, req, res, *job))
      send_error(res, 410, "expired", "the result has expired");
    return;
  }
  if (state == JobState::canceled) return send_error(res, 410, "canceled", "the job was canceled");
  // Not done yet: the documented error shape, with the status beside it to poll on.
  nlohmann::json body = svc.status(*job);
  body["error"] = {{"code", "not_done"},
                   {"message", "the job is " + std::string(to_string(state)) +
                                   "; its image is ready when the state is done"}};
  res.set_header("Retry-After", "1");
  send_json(res, 409, body);
}

void get_job_events(Service& svc, const Request& req, Response& res) {
  auto job = svc.find(req.matches[1]);
  if (!job) return send_error(res, 404, "not_found", "no job " + req.matches[1].str());
  if (!svc.acquire_stream()) {
    ApiError e;
    e.status = 503;
    e.code = "too_many_streams";
    e.message = "too many open event streams; poll /jobs/ID instead";
    e.retry_after = 2;
    return send_error(res, e);
  }
  auto state = std::make_shared<StreamState>();
  res.set_header("Cache-Control", "no-cache");
  res.set_header("X-Accel-Buffering", "no");
  res.set_chunked_content_provider(
      "text/event-stream",
      [&svc, job, state](size_t, httplib::DataSink& sink) {
        // cpp-httplib calls providers outside its exception handling: nothing may escape.
        try {
          return send_next_event(svc, job, *state, sink);
        } catch (const std::exception&) {
          return false;
        }
      },
      [&svc](bool) { svc.release_stream(); });
}

void get_jobs(Service& svc, const Request& req, Response& res) {
  if (!check_query(req, res, "GET /jobs", {})) return;
  Json list = Json::array();
  for (auto& job : svc.jobs_of(client_of(req), 100)) list.push_back(svc.status(*job));
  send_json(res, 200, {{"jobs", list}});
}

}  // namespace rayfarm::server
