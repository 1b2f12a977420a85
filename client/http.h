// The command line's HTTP client, as an interface. Its one implementation, over cpp-httplib
// (http_module.cpp), is a module of its own, rayfarm-http.so, loaded when a command first
// talks to a server: cpp-httplib brings OpenSSL, brotli and zlib, whose loading took 9 ms of
// every run of the program (a third of the lecture scene's render), talking or not.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "read_file.h"

namespace rayfarm::cli {

using HttpHeaders = std::vector<std::pair<std::string, std::string>>;

struct HttpResponse {
  int status = 0;
  std::string body;
};

// What went wrong when no response arrived (`too_large`: the body passed HttpLimits::max_body).
enum class HttpError { none, connection, read, write, unavailable, too_large, other };

// A response, or the reason there is none: `if (!res || res->status != 200)` reads as it
// did with cpp-httplib's Result.
class HttpResult {
 public:
  HttpResult() = default;
  explicit HttpResult(HttpResponse response) : ok_(true), response_(std::move(response)) {}
  HttpResult(HttpError error, std::string why) : error_(error), why_(std::move(why)) {}

  explicit operator bool() const { return ok_; }
  const HttpResponse* operator->() const { return &response_; }
  HttpError error() const { return error_; }
  const std::string& why() const { return why_; }  // the library's words for error()

 private:
  bool ok_ = false;
  HttpResponse response_;
  HttpError error_ = HttpError::other;
  std::string why_;
};

struct HttpPart {
  std::string name;
  std::string content;
  std::string filename;
  std::string content_type;
};

class HttpClient {
 public:
  virtual ~HttpClient() = default;
  virtual HttpResult get(const std::string& path, const HttpHeaders& headers) = 0;
  // A GET whose body, when the status is 200, goes to `on_data` as it arrives, until it
  // returns false. The result's body is empty.
  virtual HttpResult get_stream(const std::string& path, const HttpHeaders& headers,
                                const std::function<bool(const char*, std::size_t)>& on_data) = 0;
  virtual HttpResult post(const std::string& path, const HttpHeaders& headers,
                          const std::string& body, const std::string& content_type) = 0;
  virtual HttpResult post_multipart(const std::string& path, const HttpHeaders& headers,
                                    const std::vector<HttpPart>& parts) = 0;
  virtual HttpResult del(const std::string& path, const HttpHeaders& headers) = 0;
};

// The limits every client of the command line uses: timeouts in seconds, and the most a
// response body may hold (a server that never stops sending is refused, not stored until
// memory runs out; a streamed GET's body is its consumer's to bound).
struct HttpLimits {
  int connect = 5;
  int read = 600;
  int write = 60;
  std::uint64_t max_body = kMaxInputBytes;
};

// A client for `url` (http://HOST[:PORT] or https://...). Never null: when the module cannot
// be loaded, every request fails with HttpError::unavailable and says why.
std::unique_ptr<HttpClient> http_client(const std::string& url, const HttpLimits& limits = {});

// The module's one entry point (C linkage, so dlsym finds it by this name).
using HttpClientFactory = HttpClient* (*)(const char* url, const HttpLimits* limits);
inline constexpr const char* kHttpModuleEntry = "rayfarm_http_client";
inline constexpr const char* kHttpModuleFile = "rayfarm-http.so";

}  // namespace rayfarm::cli
