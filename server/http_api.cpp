// HttpApi: hardening (checks before routing, error and exception answers, the access log,
// connection limits) and the table of routes.
#include "http_api.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <regex>

#include "http_util.h"
#include "routes.h"

namespace rayfarm::server {
namespace {

using httplib::Request;
using httplib::Response;
using Clock = std::chrono::steady_clock;

constexpr size_t kMaxPathLength = 512;
thread_local Clock::time_point request_start;

// Client text for one line of the log: control bytes, DEL and '\\' as \xNN.
std::string log_text(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    const auto b = static_cast<unsigned char>(c);
    if (b < 0x20 || b == 0x7f || c == '\\') {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", b);
      out += hex;
    } else {
      out += c;
    }
  }
  return out;
}

bool constant_time_equal(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

// A well-formed request line whose method no route of the server takes.
bool unserved_method(const Request& req) {
  if (req.method.empty() || req.method.size() > 32 ||
      (req.version != "HTTP/1.1" && req.version != "HTTP/1.0") || req.target.empty())
    return false;
  for (const char* known : {"GET", "HEAD", "POST", "PUT", "DELETE", "OPTIONS", "PATCH"})
    if (req.method == known) return false;
  // An RFC 9110 token: anything else is a malformed request line.
  for (unsigned char c : req.method)
    if (c == 0 || !(std::isalnum(c) || std::strchr("!#$%&'*+-.^_`|~", c))) return false;
  return true;
}

}  // namespace

std::string route_label(const std::string& method_sent, const std::string& path) {
  // The method is the client's text: only the ones HTTP defines become a label (another would
  // add a series per spelling, and could close the label's quotes).
  std::string method = "OTHER";
  for (const char* known : {"GET", "HEAD", "POST", "PUT", "DELETE", "OPTIONS", "PATCH"})
    if (method_sent == known) method = known;
  // Never destroyed: a connection thread may still log a request while the process exits
  // (a server embedded without a stop, as in the fuzz harness).
  static const std::regex& job = *new std::regex(R"(^/jobs/[^/]+(/image|/events)?$)");
  std::smatch m;
  if (path.size() <= kMaxPathLength && std::regex_match(path, m, job))
    return method + " /jobs/:id" + m[1].str();
  for (const char* known :
       {"/", "/render", "/jobs", "/compare", "/grade", "/check", "/samples", "/healthz", "/metrics"})
    if (path == known) return method + " " + known;
  if (path.rfind("/web/", 0) == 0) return method + " /web/:file";
  return method + " other";
}

HttpApi::HttpApi(Service& service)
    : service_(service),
      server_(ConnectionLimits{64 * 1024, std::chrono::milliseconds(static_cast<long long>(
                                              service.settings().header_timeout * 1000))}) {
  service_.set_waiter_gone(&GuardedServer::client_gone);
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
    GuardedServer::close_after(req);
    return res.status;
  });

  server_.set_pre_routing_handler([this](const Request& req, Response& res) {
    request_start = Clock::now();
    GuardedServer::head_complete();
    // A target in absolute form is routed by its path; the library took it whole. (Told
    // from the target as sent: "http%3A//x/healthz" is no absolute form.)
    if (std::string target = origin_form(req.target); target != req.target) {
      auto& request = const_cast<Request&>(req);  // the library's own, non-const object
      request.path = origin_form(req.path);
      request.target = std::move(target);
    }
    // Only the server names the client: a header claiming a name is not the client's to send.
    const_cast<Request&>(req).headers.erase(kClientHeader);
    if (refuse(req, res)) {
      // The body (if any) is not read: it must not be taken for the next request.
      if (req.has_header("Transfer-Encoding") || req.get_header_value_count("Content-Length") > 1 ||
          (req.has_header("Content-Length") && req.get_header_value("Content-Length") != "0"))
        GuardedServer::close_after(req);
      return httplib::Server::HandlerResponse::Handled;
    }
    if (answer_preflight(req, res)) return httplib::Server::HandlerResponse::Handled;
    // (The web page and its files ignore a query: a shared link may carry one.)
    const bool page = req.path == "/" || req.path.rfind("/web/", 0) == 0;
    if (ApiError e = page ? ApiError{} : ambiguous_query(req.target)) {
      if (req.has_header("Transfer-Encoding") ||
          (req.has_header("Content-Length") && req.get_header_value("Content-Length") != "0"))
        GuardedServer::close_after(req);
      send_error(res, e);
      return httplib::Server::HandlerResponse::Handled;
    }
    // A request with neither Content-Length nor Transfer-Encoding has an empty body (RFC 9112
    // §6.3), as `curl -X POST URL` sends it; this cpp-httplib would read until the client
    // gave up instead.
    if (!req.has_header("Content-Length") && !req.has_header("Transfer-Encoding"))
      const_cast<Request&>(req).headers.emplace("Content-Length", "0");
    // A media type is case-insensitive (RFC 9110 §8.3.1), but this cpp-httplib matches
    // "multipart/form-data" as written: the type is given in lower case (the boundary, a
    // parameter whose case counts, as sent).
    if (const std::string type = req.get_header_value("Content-Type"); !type.empty()) {
      const size_t semi = std::min(type.find(';'), type.size());
      const std::string lowered = lower_ascii(type.substr(0, semi)) + type.substr(semi);
      if (lowered != type) {
        auto& headers = const_cast<Request&>(req).headers;  // the library's own object
        headers.erase("Content-Type");
        headers.emplace("Content-Type", lowered);
      }
    }
    // curl --data-binary labels a scene as a urlencoded form; this cpp-httplib would then
    // parse the scene as query parameters and refuse bodies over 8 KiB. A scene is text.
    if (req.get_header_value("Content-Type").rfind("application/x-www-form-urlencoded", 0) == 0) {
      auto& headers = const_cast<Request&>(req).headers;  // the library's own, non-const object
      headers.erase("Content-Type");
      headers.emplace("Content-Type", "text/plain");
      headers.emplace(kFormEncodedMark, "1");  // for a hint if the scene is one line (curl -d)
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });

  // Cross-origin answers carry the CORS headers for the one configured origin only, errors
  // included (a grader's page must be able to read a 401 or a 429).
  server_.set_post_routing_handler([this](const Request& req, Response& res) {
    // The library offers byte ranges on HEAD answers; none are served (pre-routing, below).
    if (req.method == "HEAD") res.headers.erase("Accept-Ranges");
    // It also says "Content-Length: 0" of every empty answer. A 204 must not say a length,
    // and a 304 may only say the image's own (RFC 9110 §8.6): a cache would take 0 for it.
    if (res.status == 204 || res.status == 304) res.headers.erase("Content-Length");
    const std::string& origin = service_.settings().cors_origin;
    if (origin.empty()) return;
    res.set_header("Vary", "Origin");
    if (req.get_header_value("Origin") != origin) return;
    res.set_header("Access-Control-Allow-Origin", origin);
    res.set_header("Access-Control-Expose-Headers",
                   "Location, Retry-After, ETag, X-Job-Id, X-Job-State, X-Render-Ms, X-Cache, "
                   "Idempotent-Replayed, X-Compare-Differing-Pixels, X-Compare-Differing-Fraction, "
                   "X-Compare-Rmse, X-Compare-Psnr, X-Compare-Max-Abs, X-Compare-Identical, "
                   "X-Compare-Match");
  });

  server_.set_exception_handler([](const Request&, Response& res, std::exception_ptr ep) {
    // Never echo the exception text: it may carry internals.
    res.headers.clear();
    try {
      if (ep) std::rethrow_exception(ep);
    } catch (const Unavailable&) {
      // A farm node whose Redis does not answer: nothing is lost, try again shortly.
      ApiError e = api_error(503, "redis_unavailable",
                             "the farm's job store is unavailable; try again shortly");
      e.retry_after = 2;
      return send_error(res, e);
    } catch (...) {
    }
    send_error(res, 500, "internal_error", "internal server error");
  });

  server_.set_error_handler(httplib::Server::HandlerWithResponse([](const Request& req, Response& res) {
    if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;
    switch (res.status) {
      case 404: {
        // A known path asked with another method: 405 and what it allows.
        const std::string allow = allowed_methods(req.path);
        if (!allow.empty()) {
          res.set_header("Allow", allow);
          send_error(res, 405, "method_not_allowed",
                     req.method.substr(0, 16) + " " + req.path.substr(0, 100) + " is not served; " +
                         "it takes " + allow);
          res.status = 405;
          break;
        }
        send_error(res, 404, "not_found",
                   "no such resource: " + req.path.substr(0, 100) + " (GET / lists the routes)");
        break;
      }
      case 400:
        // A well-formed request whose method the server has no route for at all (BREW,
        // TRACE, CONNECT): 501, as HTTP asks, rather than "bad request".
        if (unserved_method(req)) {
          GuardedServer::close_after(req);  // its body, if any, is not read
          send_error(res, 501, "not_implemented",
                     "the method " + req.method.substr(0, 16) +
                         " is not implemented: rayfarmd serves GET, HEAD, POST, DELETE and OPTIONS");
          res.status = 501;
          break;
        }
        // The library's own refusals, said as what they are; the connection ends after each.
        if (GuardedServer::body_cut_short()) {
          GuardedServer::close_after(req);
          send_error(res, 408, "request_timeout",
                     "the request body stopped before its Content-Length: it arrived slower "
                     "than 8 KiB a second, or the client stopped sending it");
          res.status = 408;
        } else if (!GuardedServer::head_read()) {
          GuardedServer::close_after(req);
          send_error(res, 400, "http_error",
                     "the request line or a header could not be read: a malformed line, or "
                     "one longer than 8 KiB");
        } else if (req.is_multipart_form_data()) {
          GuardedServer::close_after(req);
          send_error(res, 400, "bad_multipart",
                     "the multipart/form-data body could not be read: each part starts with "
                     "--BOUNDARY (the boundary of its Content-Type) and has a "
                     "Content-Disposition with a name, and the body ends with --BOUNDARY--");
        } else {
          GuardedServer::close_after(req);
          send_error(res, 400, "http_error", "the request body could not be read");
        }
        break;
      case 405: send_error(res, 405, "method_not_allowed", "method not allowed"); break;
      case 413: send_error(res, 413, "body_too_large", "the request body is too large"); break;
      case 414: send_error(res, 414, "uri_too_long", "the request line is too long"); break;
      case 416:
        // Only the library answers this here: a Range header that is not a byte range.
        send_error(res, 416, "range_not_satisfiable",
                   "the Range header is not a byte range (bytes=FIRST-LAST); ranges are not "
                   "offered: send the request without one for the whole resource");
        break;
      default: send_error(res, res.status, "http_error", "the request could not be served");
    }
    return httplib::Server::HandlerResponse::Handled;
  }));

  server_.set_logger([this](const Request& req, const Response& res) {
    double ms = std::chrono::duration<double, std::milli>(Clock::now() - request_start).count();
    // A method the library does not take leaves the path unparsed: the target's says it.
    const std::string path =
        req.path.empty() ? req.target.substr(0, req.target.find('?')) : req.path;
    service_.metrics().request(route_label(req.method, path), res.status);
    if (service_.settings().access_log) {
      // When, what, the answer, and who: by roster name where there is one.
      char when[32];
      const std::time_t now = std::time(nullptr);
      std::tm tm{};
      gmtime_r(&now, &tm);
      std::strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", &tm);
      // The path is the client's text, decoded: a line break or a terminal's escape in it
      // would forge or hide lines of the log.
      std::fprintf(stderr, "%s %s %s %d %zu %.1fms %s\n", when, log_text(req.method).c_str(),
                   log_text(req.path.substr(0, 200)).c_str(), res.status, res.body.size(), ms,
                   log_text(client_of(req)).c_str());
    }
  });
}

bool HttpApi::refuse(const Request& req, Response& res) const {
  const Settings& st = service_.settings();
  if (req.path.size() > kMaxPathLength) {
    send_error(res, 414, "uri_too_long", "the request path is too long");
    return true;
  }
  // A header name with white space in it ("Content-Length : 5") is not that header to this
  // server, and may be to another on the way: refused, and the connection closed (RFC 9112
  // §5.1), so that its body is never read as a request.
  for (const auto& [name, value] : req.headers)
    if (name.find_first_of(" \t") != std::string::npos) {
      send_error(res, 400, "bad_header", "a header's name has white space in it");
      GuardedServer::close_after(req);
      return true;
    }
  // A header folded onto the line before (RFC 9112 §5.2): refused, as an intermediary that
  // unfolds it and one that does not would read two different requests.
  if (GuardedServer::folded_header()) {
    send_error(res, 400, "bad_header",
               "a header line begins with white space (obsolete line folding): send each "
               "header on a line of its own");
    GuardedServer::close_after(req);
    return true;
  }
  // A framing header with an empty value is dropped by the library, which then reads no
  // body: the bytes sent as one would be read as the next request.
  for (const std::string_view name : {"Content-Length", "Transfer-Encoding", "Content-Encoding"})
    if (GuardedServer::empty_header(name)) {
      send_error(res, 400, name == "Content-Length" ? "bad_content_length" : "bad_header",
                 "the request's " + std::string(name) + " header is empty");
      GuardedServer::close_after(req);
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
  if (req.has_header("Content-Encoding") &&
      lower_ascii(trim(req.get_header_value("Content-Encoding"))) != "identity") {
    send_error(res, 415, "unsupported_encoding",
               "compressed request bodies are not accepted; send the body uncompressed");
    return true;
  }
  if (req.has_header("Content-Length")) {
    // One length, in digits (RFC 9112 §6.3): two, or one a proxy might read otherwise, would
    // let a body be taken for the next request.
    const std::string v = req.get_header_value("Content-Length");
    const bool digits =
        !v.empty() && std::all_of(v.begin(), v.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (req.get_header_value_count("Content-Length") > 1 || !digits) {
      send_error(res, 400, "bad_content_length",
                 "the request must have one Content-Length, a number of bytes in digits");
      GuardedServer::close_after(req);
      return true;
    }
    // The library reads a body for POST, PUT, PATCH and DELETE only: on any other method
    // one would be read as the next request.
    const bool takes_body = req.method == "POST" || req.method == "PUT" ||
                            req.method == "PATCH" || req.method == "DELETE";
    if (!takes_body && v.find_first_not_of('0') != std::string::npos) {
      send_error(res, 400, "unexpected_body",
                 req.method.substr(0, 16) + " requests take no body; send none");
      return true;
    }
    if (v.size() >= 19 || std::stoull(v) > st.max_body_bytes) {
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
  // Ranges are not offered (no Accept-Ranges): a many-part request would multiply a
  // response, and the library answers a single range with a slice under status 200, which a
  // client would take for the whole image. The whole resource is always sent.
  const bool many_ranges = req.ranges.size() > 1;
  const_cast<Request&>(req).ranges.clear();  // the library's own object
  if (many_ranges) {
    send_error(res, 416, "range_not_satisfiable", "multi-range requests are not supported");
    return true;
  }
  const bool roster = !st.tokens_file.empty();
  if ((roster || !st.tokens.empty()) && !open_to_all(req)) {
    std::string token = bearer_token(req);
    bool ok = false;
    if (roster && !token.empty()) {
      if (std::optional<RosterEntry> who = service_.roster().find(token)) {
        auto& headers = const_cast<Request&>(req).headers;  // the library's own object
        headers.erase(kClientHeader);
        headers.emplace(kClientHeader, "name:" + who->name);
        ok = true;
      }
    }
    for (const std::string& t : st.tokens) ok |= constant_time_equal(token, t);
    if (!ok) {
      res.set_header("WWW-Authenticate", "Bearer");
      send_error(res, 401, "unauthorized", "a valid bearer token is required");
      return true;
    }
  }
  return false;
}

bool HttpApi::open_to_all(const Request& req) {
  if (req.path == "/healthz" || req.path == "/metrics") return true;
  // The page and its files hold no one's data, and a browser cannot send a token to load
  // them: the page asks for the token and sends it on its own requests.
  const bool get = req.method == "GET" || req.method == "HEAD";
  if (get && (req.path == "/" || req.path.rfind("/web/", 0) == 0)) return true;
  // A CORS preflight never carries credentials; it is answered, or refused, by its origin.
  return req.method == "OPTIONS";
}

bool HttpApi::answer_preflight(const Request& req, Response& res) const {
  const std::string& origin = service_.settings().cors_origin;
  if (req.method != "OPTIONS" || origin.empty() || req.get_header_value("Origin") != origin ||
      !req.has_header("Access-Control-Request-Method"))
    return false;
  // Unknown paths fall through to the 404, which the browser takes as a refusal.
  const std::string allow = allowed_methods(req.path);
  if (allow.empty()) return false;
  res.status = 204;
  res.set_header("Access-Control-Allow-Methods", allow);
  res.set_header("Access-Control-Allow-Headers", "Authorization, Content-Type, Idempotency-Key");
  res.set_header("Access-Control-Max-Age", "600");
  return true;
}

namespace {

struct RouteInfo {
  const char* method;
  const char* pattern;  // as bound
  const char* shown;    // as the index shows it
  const char* what;
};

constexpr RouteInfo kRoutes[] = {
    {"POST", "/render", "/render", "render a scene (body, multipart, or ?sample=NAME); wait=1 answers the image"},
    {"GET", R"(/jobs/([0-9a-f]{32}))", "/jobs/ID", "a job's status"},
    {"DELETE", R"(/jobs/([0-9a-f]{32}))", "/jobs/ID", "cancel a job"},
    {"GET", R"(/jobs/([0-9a-f]{32})/image)", "/jobs/ID/image", "a job's image"},
    {"GET", R"(/jobs/([0-9a-f]{32})/events)", "/jobs/ID/events", "a job's progress (server-sent events)"},
    {"GET", "/jobs", "/jobs", "your recent jobs"},
    {"POST", "/compare", "/compare", "compare two images, or a scene's render with an image"},
    {"POST", "/grade", "/grade", "grade a student's images against an assignment"},
    {"POST", "/check", "/check", "a scene's errors and warnings, without rendering it (course=1: the course program's too)"},
    {"GET", "/samples", "/samples", "the bundled scenes"},
    {"GET", "/healthz", "/healthz", "liveness and queue figures"},
    {"GET", "/metrics", "/metrics", "Prometheus metrics"},
    {"GET", "/", "/", "this list (the web page for a browser)"},
    {"GET", R"(/web/([A-Za-z0-9_-]+\.[a-z]+))", "/web/FILE", "the web page's scripts and styles"},
};

}  // namespace

std::string allowed_methods(const std::string& path) {
  std::string allow;
  auto add = [&allow](const std::string& method) {
    if (allow.find(method) == std::string::npos) allow += (allow.empty() ? "" : ", ") + method;
  };
  for (const RouteInfo& r : kRoutes)
    if (std::regex_match(path, std::regex(r.pattern))) {
      add(r.method);
      if (std::string_view(r.method) == "GET") add("HEAD");  // the library answers HEAD as GET
    }
  return allow;
}

void get_index(Service& svc, const Request& req, Response& res) {
  // One address for people and programs: a browser asks for HTML, curl for anything.
  res.set_header("Vary", "Accept");
  if (wants_page(req)) return get_page(svc, req, res);
  nlohmann::json routes = nlohmann::json::array();
  for (const RouteInfo& r : kRoutes)
    routes.push_back({{"method", r.method}, {"path", r.shown}, {"what", r.what}});
  send_json(res, 200, {{"service", "rayfarmd"},
                       {"routes", routes},
                       {"try", "curl --data-binary @scene.txt 'HOST/render?wait=1' -o out.png"}});
}

void HttpApi::routes() {
  auto to = [this](RouteHandler handler) {
    return [this, handler](const Request& req, Response& res) {
      // The library takes a part without a name (a Content-Disposition with no name="...")
      // as the part "": no route names one, so no route has to tell it from a missing part.
      if (req.is_multipart_form_data() && req.files.count("") > 0) {
        GuardedServer::close_after(req);
        return send_error(res, 400, "bad_multipart",
                          "a part of the multipart/form-data body has no name: each part's "
                          "Content-Disposition needs name=\"...\"");
      }
      handler(service_, req, res);
    };
  };
  server_.Post("/render", to(post_render));
  server_.Get(R"(/jobs/([0-9a-f]{32}))", to(get_job));
  server_.Delete(R"(/jobs/([0-9a-f]{32}))", to(delete_job));
  server_.Get(R"(/jobs/([0-9a-f]{32})/image)", to(get_job_image));
  server_.Get(R"(/jobs/([0-9a-f]{32})/events)", to(get_job_events));
  server_.Get("/jobs", to(get_jobs));
  server_.Post("/compare", to(post_compare));
  server_.Post("/grade", to(post_grade));
  server_.Post("/check", to(post_check));
  server_.Get("/samples", to(get_samples));
  server_.Get("/healthz", to(get_healthz));
  server_.Get("/metrics", to(get_metrics));
  server_.Get("/", to(get_index));
  server_.Get(R"(/web/([A-Za-z0-9_-]+\.[a-z]+))", to(get_web_file));
}

int HttpApi::bind(const std::string& host, int port) {
  const int bound = port == 0 ? server_.bind_to_any_port(host)
                              : (server_.bind_to_port(host, port) ? port : -1);
  if (bound > 0) server_.widen_backlog();
  return bound;
}

bool HttpApi::listen() { return server_.listen_after_bind(); }

void HttpApi::stop() { server_.stop(); }

}  // namespace rayfarm::server
