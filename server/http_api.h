// The HTTP API of SPEC §5 on cpp-httplib, with the library's known weaknesses closed here:
// chunked and compressed uploads refused (they bypass the payload limit), multi-range
// requests refused, exceptions answered with a generic JSON 500, the client address taken
// from the socket only, path length bounded, and a connection pool sized so that waiting
// clients cannot starve health and status requests.
#pragma once

#include <httplib.h>

#include <memory>

#include "service.h"

namespace rayfarm::server {

class HttpApi {
 public:
  explicit HttpApi(Service& service);

  // Binds to host:port (port 0: any free port) and returns the port, or -1.
  int bind(const std::string& host, int port);
  bool listen();  // blocks until stop()
  void stop();

  httplib::Server& http() { return server_; }

 private:
  void routes();
  void harden();

  Service& service_;
  httplib::Server server_;
};

// The route a path belongs to, for metrics and logs: "/jobs/:id/image", ...
std::string route_label(const std::string& method, const std::string& path);

}  // namespace rayfarm::server
