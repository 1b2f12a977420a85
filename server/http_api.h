// The HTTP API (docs/http-api.md) on cpp-httplib: each route bound to its handler (routes.h),
// and the library's known weaknesses closed: chunked and compressed uploads refused (they
// bypass the payload limit), also before a `100 Continue`, multi-range requests refused,
// exceptions answered with a generic JSON 500, the client address taken from the socket only,
// path length bounded, and a connection pool sized so that waiting clients cannot starve
// health and status requests. Browsers from the one --cors-origin origin may call it. The request head limits and the connection loop are in
// connection.h.
#pragma once

#include <httplib.h>

#include <memory>

#include "connection.h"
#include "service.h"

namespace rayfarm::server {

class HttpApi {
 public:
  explicit HttpApi(Service& service);

  // Binds to host:port (port 0: any free port) and returns the port, or -1.
  int bind(const std::string& host, int port);
  bool listen();  // blocks until stop()
  void stop();
  int open_connections() const { return server_.open_connections(); }

  httplib::Server& http() { return server_; }

 private:
  void routes();
  void harden();
  // Answers a request that must not be served before its body is read; true when refused.
  bool refuse(const httplib::Request& req, httplib::Response& res) const;
  // Requests served without a token: health, metrics, the page and CORS preflights.
  static bool open_to_all(const httplib::Request& req);
  // Answers a CORS preflight from the --cors-origin origin; true when answered.
  bool answer_preflight(const httplib::Request& req, httplib::Response& res) const;

  Service& service_;
  GuardedServer server_;
};

// The route a path belongs to, for metrics and logs: "/jobs/:id/image", ...
std::string route_label(const std::string& method, const std::string& path);

}  // namespace rayfarm::server
