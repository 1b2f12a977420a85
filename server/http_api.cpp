// HTTP routes and hardening.
#include "http_api.h"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <regex>
#include <set>

#include "rayfarm/compare.h"
#include "rayfarm/image_io.h"
#include "rayfarm/sha256.h"

namespace rayfarm::server {
namespace {

using httplib::Request;
using httplib::Response;
using Json = nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr size_t kMaxPathLength = 512;
thread_local Clock::time_point request_start;

void send_json(Response& res, int status, const Json& body) {
  res.status = status;
  res.set_content(json_text(body) + "\n", "application/json");
}

void send_error(Response& res, const ApiError& e) {
  if (e.retry_after > 0) res.set_header("Retry-After", std::to_string(e.retry_after));
  send_json(res, e.status, e.body());
}

void send_error(Response& res, int status, const std::string& code, const std::string& message) {
  ApiError e;
  e.status = status;
  e.code = code;
  e.message = message;
  send_error(res, e);
}

bool constant_time_equal(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

std::string bearer_token(const Request& req) {
  std::string auth = req.get_header_value("Authorization");
  const std::string prefix = "Bearer ";
  if (auth.size() > prefix.size() && auth.compare(0, prefix.size(), prefix) == 0)
    return auth.substr(prefix.size());
  return {};
}

// Who is asking: the bearer token's digest, else the socket's address (never a header).
std::string client_of(const Request& req) {
  std::string token = bearer_token(req);
  if (!token.empty()) return "token:" + sha256_hex(token).substr(0, 16);
  return "addr:" + req.remote_addr;
}

bool param_true(const Request& req, const char* name) {
  if (!req.has_param(name)) return false;
  std::string v = req.get_param_value(name);
  return v == "1" || v == "true" || v == "yes";
}

void send_image(Response& res, const Image& image, bool ppm) {
  auto bytes = encode_image(image, ppm ? ImageFormat::ppm : ImageFormat::png);
  res.status = 200;
  res.set_content(reinterpret_cast<const char*>(bytes.data()), bytes.size(),
                  ppm ? "image/x-portable-pixmap" : "image/png");
}

bool wants_ppm(const Request& req, const Job& job) {
  if (req.has_param("format")) return req.get_param_value("format") == "ppm";
  return job.options.format == ImageFormat::ppm;
}

// Sends a finished job's result with its caching headers; false when it has expired.
bool send_result(Service& service, const Request& req, Response& res, const Job& job) {
  auto png = service.result_png(job);
  if (!png) return false;
  std::string etag = "\"" + job.image_name + (wants_ppm(req, job) ? "-ppm" : "") + "\"";
  res.set_header("ETag", etag);
  res.set_header("Cache-Control", "private, max-age=86400");
  res.set_header("X-Job-Id", job.id);
  {
    std::lock_guard lock(job.mu);
    res.set_header("X-Render-Ms", std::to_string(std::llround(job.stats.render_ms)));
    res.set_header("X-Cache", job.cache_hit ? "hit" : "miss");
  }
  if (req.get_header_value("If-None-Match") == etag) {
    res.status = 304;
    return true;
  }
  if (wants_ppm(req, job)) {
    std::string error;
    auto image = decode_image(*png, &error);
    if (!image) return false;
    send_image(res, *image, true);
    return true;
  }
  res.status = 200;
  res.set_content(*png, "image/png");
  return true;
}

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

const std::set<std::string> kControlParams = {"wait", "sample"};

}  // namespace

std::string route_label(const std::string& method, const std::string& path) {
  static const std::regex job(R"(^/jobs/[^/]+(/image|/events)?$)");
  std::smatch m;
  if (path.size() <= kMaxPathLength && std::regex_match(path, m, job))
    return method + " /jobs/:id" + m[1].str();
  for (const char* known : {"/render", "/jobs", "/compare", "/samples", "/healthz", "/metrics"})
    if (path == known) return method + " " + known;
  return method + " other";
}

HttpApi::HttpApi(Service& service)
    : service_(service),
      server_(ConnectionLimits{64 * 1024, std::chrono::milliseconds(static_cast<long long>(
                                              service.settings().header_timeout * 1000))}) {
  harden();
  routes();
}

void HttpApi::harden() {
  const Settings& s = service_.settings();
  const int threads = std::max(8, s.http_threads);
  server_.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  // Headers and body go out in separate writes: without TCP_NODELAY, Nagle's algorithm and
  // the client's delayed ACK add 40 ms to every keep-alive response.
  server_.set_tcp_nodelay(true);
  // The library's default also sets SO_REUSEPORT, which would let a second server share the
  // port silently; a second rayfarmd on a busy port should fail instead.
  server_.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  server_.set_keep_alive_max_count(100);
  server_.set_keep_alive_timeout(2);
  server_.set_read_timeout(10, 0);
  server_.set_write_timeout(10, 0);
  server_.set_payload_max_length(s.max_body_bytes);

  server_.set_expect_100_continue_handler([this](const Request& req, Response& res) {
    // cpp-httplib would answer `100 Continue` before the pre-routing handler runs: check first,
    // so that a client is never asked to send a body that is refused.
    GuardedServer::head_complete();
    if (!refuse(req, res)) return 100;
    GuardedServer::close_after(res);
    return res.status;
  });

  server_.set_pre_routing_handler([this](const Request& req, Response& res) {
    request_start = Clock::now();
    GuardedServer::head_complete();
    if (refuse(req, res)) {
      // The body (if any) is not read: it must not be taken for the next request.
      if (req.has_header("Transfer-Encoding") ||
          (req.has_header("Content-Length") && req.get_header_value("Content-Length") != "0"))
        GuardedServer::close_after(res);
      return httplib::Server::HandlerResponse::Handled;
    }
    // curl --data-binary labels a scene as a urlencoded form; this cpp-httplib would then
    // parse the scene as query parameters and refuse bodies over 8 KiB. A scene is text.
    if (req.get_header_value("Content-Type").rfind("application/x-www-form-urlencoded", 0) == 0) {
      auto& headers = const_cast<Request&>(req).headers;  // the library's own, non-const object
      headers.erase("Content-Type");
      headers.emplace("Content-Type", "text/plain");
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });

  server_.set_exception_handler([](const Request&, Response& res, std::exception_ptr) {
    // Never echo the exception text: it may carry internals.
    res.headers.clear();
    send_error(res, 500, "internal_error", "internal server error");
  });

  server_.set_error_handler(httplib::Server::HandlerWithResponse([](const Request& req, Response& res) {
    if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;
    switch (res.status) {
      case 404: send_error(res, 404, "not_found", "no such resource: " + req.path.substr(0, 100)); break;
      case 405: send_error(res, 405, "method_not_allowed", "method not allowed"); break;
      case 413: send_error(res, 413, "body_too_large", "the request body is too large"); break;
      case 414: send_error(res, 414, "uri_too_long", "the request line is too long"); break;
      case 416: send_error(res, 416, "range_not_satisfiable", "the range is not satisfiable"); break;
      default: send_error(res, res.status, "http_error", "the request could not be served");
    }
    return httplib::Server::HandlerResponse::Handled;
  }));

  server_.set_logger([this](const Request& req, const Response& res) {
    double ms = std::chrono::duration<double, std::milli>(Clock::now() - request_start).count();
    service_.metrics().request(route_label(req.method, req.path), res.status);
    if (service_.settings().access_log)
      std::fprintf(stderr, "%s %s %d %zu %.1fms %s\n", req.method.c_str(),
                   req.path.substr(0, 200).c_str(), res.status, res.body.size(), ms,
                   client_of(req).c_str());
  });
}

bool HttpApi::refuse(const Request& req, Response& res) const {
  const Settings& st = service_.settings();
  if (req.path.size() > kMaxPathLength) {
    send_error(res, 414, "uri_too_long", "the request path is too long");
    return true;
  }
  // Chunked bodies skip the payload limit in this cpp-httplib; compressed ones are inflated
  // without limit. Neither is needed by any client of this API.
  if (req.has_header("Transfer-Encoding")) {
    send_error(res, 411, "length_required",
               "chunked or otherwise transfer-encoded request bodies are not accepted; send "
               "the body with a Content-Length");
    return true;
  }
  if (req.has_header("Content-Encoding") && req.get_header_value("Content-Encoding") != "identity") {
    send_error(res, 415, "unsupported_encoding",
               "compressed request bodies are not accepted; send the body uncompressed");
    return true;
  }
  if (req.has_header("Content-Length")) {
    const std::string v = req.get_header_value("Content-Length");
    bool digits = !v.empty() && v.size() < 19 &&
                  std::all_of(v.begin(), v.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (!digits || std::stoull(v) > st.max_body_bytes) {
      ApiError e;
      e.status = 413;
      e.code = "body_too_large";
      e.limit = "max_body_bytes";
      e.message = "the request body is over the limit of " + std::to_string(st.max_body_bytes) +
                  " bytes";
      send_error(res, e);
      return true;
    }
  }
  // One response sent once: a many-part Range request would multiply it.
  if (req.ranges.size() > 1) {
    send_error(res, 416, "range_not_satisfiable", "multi-range requests are not supported");
    return true;
  }
  if (!st.tokens.empty() && req.path != "/healthz" && req.path != "/metrics") {
    std::string token = bearer_token(req);
    bool ok = false;
    for (const std::string& t : st.tokens) ok |= constant_time_equal(token, t);
    if (!ok) {
      res.set_header("WWW-Authenticate", "Bearer");
      send_error(res, 401, "unauthorized", "a valid bearer token is required");
      return true;
    }
  }
  return false;
}

void HttpApi::routes() {
  Service& svc = service_;

  server_.Post("/render", [&svc](const Request& req, Response& res) {
    std::string text;
    if (req.has_param("sample")) {
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
    } else if (req.is_multipart_form_data()) {
      if (!req.has_file("scene"))
        return send_error(res, 400, "missing_scene", "multipart upload without a 'scene' part");
      text = req.get_file_value("scene").content;
    } else {
      text = req.body;
    }
    if (text.find_first_not_of(" \t\r\n") == std::string::npos)
      return send_error(res, 400, "empty_scene",
                        "the request has no scene: send a model file or a JSON scene as the body");
    Params params;
    for (auto& [k, v] : req.params)
      if (!kControlParams.count(k)) params.emplace_back(k, v);
    Submitted sub = svc.submit(text, params, client_of(req));
    if (sub.error) return send_error(res, sub.error);
    auto& job = *sub.job;

    if (param_true(req, "wait")) {
      if (!svc.acquire_waiter()) {
        res.set_header("X-Wait", "unavailable");
      } else {
        struct Release {
          Service& s;
          ~Release() { s.release_waiter(); }
        } release{svc};
        std::unique_lock lock(job.mu);
        while (!is_final(job.state) && !svc.stopped())
          job.changed.wait_for(lock, std::chrono::milliseconds(500));
        JobState state = job.state;
        std::string code = job.error_code, message = job.error;
        lock.unlock();
        if (state == JobState::done) {
          if (!send_result(svc, req, res, job))
            send_error(res, 410, "expired", "the result has already expired");
          return;
        }
        if (state == JobState::canceled)
          return send_error(res, 410, "canceled", "the job was canceled");
        if (state == JobState::failed) {
          ApiError e;
          e.status = code == "timeout" ? 422 : code == "storage_error" ? 503 : 500;
          e.code = code.empty() ? "render_failed" : code;
          e.message = message;
          if (code == "timeout") e.limit = "job_timeout";
          return send_error(res, e);
        }
        // Shutting down: the job is persisted and the client can poll for it.
      }
    }
    JobState state;
    {
      std::lock_guard lock(job.mu);  // a worker may be starting it
      state = job.state;
    }
    Json body = {{"id", job.id},
                 {"state", to_string(state)},
                 {"queue_position", svc.queue_position(job)},
                 {"links",
                  {{"self", "/jobs/" + job.id},
                   {"image", "/jobs/" + job.id + "/image"},
                   {"events", "/jobs/" + job.id + "/events"}}}};
    res.set_header("Location", "/jobs/" + job.id);
    send_json(res, 202, body);
  });

  server_.Get(R"(/jobs/([0-9a-f]{32}))", [&svc](const Request& req, Response& res) {
    auto job = svc.find(req.matches[1]);
    if (!job) return send_error(res, 404, "not_found", "no job " + req.matches[1].str());
    send_json(res, 200, svc.status(*job));
  });

  server_.Delete(R"(/jobs/([0-9a-f]{32}))", [&svc](const Request& req, Response& res) {
    ApiError e = svc.cancel(req.matches[1], client_of(req));
    if (e) return send_error(res, e);
    auto job = svc.find(req.matches[1]);
    send_json(res, 200, svc.status(*job));
  });

  server_.Get(R"(/jobs/([0-9a-f]{32})/image)", [&svc](const Request& req, Response& res) {
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
    send_json(res, 409, svc.status(*job));
  });

  server_.Get(R"(/jobs/([0-9a-f]{32})/events)", [&svc](const Request& req, Response& res) {
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
  });

  server_.Get("/jobs", [&svc](const Request& req, Response& res) {
    Json list = Json::array();
    for (auto& job : svc.jobs_of(client_of(req), 100)) list.push_back(svc.status(*job));
    send_json(res, 200, {{"jobs", list}});
  });

  server_.Post("/compare", [&svc](const Request& req, Response& res) {
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
      Submitted sub = svc.submit(req.get_file_value("scene").content, params, client_of(req));
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
    Json body = {{"width", result->width},
                 {"height", result->height},
                 {"rmse", result->rmse},
                 {"psnr", std::isinf(result->psnr) ? Json(nullptr) : Json(result->psnr)},
                 {"identical", result->max_abs == 0},
                 {"max_abs", result->max_abs},
                 {"mean_abs", result->mean_abs},
                 {"differing_pixels", result->differing_pixels},
                 {"differing_fraction", result->differing_fraction},
                 {"off_by_more_than_1", result->off_by_more_than_1},
                 {"threshold", options.threshold},
                 {"neighborhood", options.neighborhood}};
    if (!job_id.empty()) body["reference_job"] = job_id;
    send_json(res, 200, body);
  });

  server_.Get("/samples", [&svc](const Request&, Response& res) {
    Json list = Json::array();
    for (const Sample& s : svc.samples())
      list.push_back({{"name", s.name},
                      {"description", s.description},
                      {"render", "/render?sample=" + s.name}});
    send_json(res, 200, {{"samples", list}});
  });

  server_.Get("/healthz", [&svc](const Request&, Response& res) {
    send_json(res, svc.shutting_down() ? 503 : 200, svc.health());
  });

  server_.Get("/metrics", [&svc](const Request&, Response& res) {
    res.set_content(svc.metrics_text(), "text/plain; version=0.0.4");
  });
}

int HttpApi::bind(const std::string& host, int port) {
  if (port == 0) return server_.bind_to_any_port(host);
  return server_.bind_to_port(host, port) ? port : -1;
}

bool HttpApi::listen() { return server_.listen_after_bind(); }

void HttpApi::stop() { server_.stop(); }

}  // namespace rayfarm::server
