// rayfarm-http.so: the command line's HTTP client (http.h) over cpp-httplib, built as a module
// that the program loads only when it talks to a server.
#include <httplib.h>

#include <random>

#include "http.h"

namespace rayfarm::cli {
namespace {

httplib::Headers headers_of(const HttpHeaders& h) { return {h.begin(), h.end()}; }

// multipart/form-data (RFC 7578), built here so that every request goes through send() with
// the body's bound. The boundary is random, and checked against the parts' bytes.
std::string multipart_body(const std::vector<HttpPart>& parts, std::string& boundary) {
  std::random_device seed;
  std::mt19937_64 rng((static_cast<std::uint64_t>(seed()) << 32) ^ seed());
  for (;;) {
    boundary = "rayfarm-";
    for (int i = 0; i < 24; ++i) boundary += "0123456789abcdef"[rng() % 16];
    bool clash = false;
    for (const HttpPart& p : parts) clash = clash || p.content.find(boundary) != std::string::npos;
    if (!clash) break;
  }
  // In a quoted name, the three characters that would end it or its line are escaped as an
  // HTML form escapes them.
  auto quoted = [](const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
      if (c == '"') out += "%22";
      else if (c == '\r') out += "%0D";
      else if (c == '\n') out += "%0A";
      else out += c;
    }
    return out + "\"";
  };
  std::string body;
  for (const HttpPart& p : parts) {
    body += "--" + boundary + "\r\nContent-Disposition: form-data; name=" + quoted(p.name);
    if (!p.filename.empty()) body += "; filename=" + quoted(p.filename);
    body += "\r\n";
    if (!p.content_type.empty()) body += "Content-Type: " + p.content_type + "\r\n";
    body += "\r\n" + p.content + "\r\n";
  }
  return body + "--" + boundary + "--\r\n";
}

class HttplibClient final : public HttpClient {
 public:
  HttplibClient(const std::string& url, const HttpLimits& limits)
      : client_(url), max_body_(limits.max_body) {
    client_.set_connection_timeout(limits.connect, 0);
    client_.set_read_timeout(limits.read, 0);
    client_.set_write_timeout(limits.write, 0);
  }

  HttpResult get(const std::string& path, const HttpHeaders& headers) override {
    return send(request("GET", path, headers));
  }

  HttpResult get_stream(const std::string& path, const HttpHeaders& headers,
                        const std::function<bool(const char*, std::size_t)>& on_data) override {
    httplib::Request req = request("GET", path, headers);
    req.response_handler = [](const httplib::Response& r) { return r.status == 200; };
    req.content_receiver = [&on_data](const char* data, std::size_t size, std::uint64_t,
                                      std::uint64_t) { return on_data(data, size); };
    return result_of(client_.send(req));
  }

  HttpResult post(const std::string& path, const HttpHeaders& headers, const std::string& body,
                  const std::string& content_type) override {
    httplib::Request req = request("POST", path, headers);
    if (!content_type.empty()) req.set_header("Content-Type", content_type);
    req.body = body;
    return send(std::move(req));
  }

  HttpResult post_multipart(const std::string& path, const HttpHeaders& headers,
                            const std::vector<HttpPart>& parts) override {
    httplib::Request req = request("POST", path, headers);
    std::string boundary;
    req.body = multipart_body(parts, boundary);
    req.set_header("Content-Type", "multipart/form-data; boundary=" + boundary);
    return send(std::move(req));
  }

  HttpResult del(const std::string& path, const HttpHeaders& headers) override {
    return send(request("DELETE", path, headers));
  }

 private:
  static httplib::Request request(const std::string& method, const std::string& path,
                                  const HttpHeaders& headers) {
    httplib::Request req;
    req.method = method;
    req.path = path;
    req.headers = headers_of(headers);
    return req;
  }

  // The body is gathered here, not by the library (which grows it without end): a declared
  // length past the bound is refused before any of it is stored, and a stream that passes it
  // stops there.
  HttpResult send(httplib::Request req) {
    std::string body;
    bool too_large = false;
    req.content_receiver = [&](const char* data, std::size_t size, std::uint64_t,
                               std::uint64_t declared) {
      if (declared > max_body_ || body.size() + size > max_body_) {
        too_large = true;
        return false;
      }
      body.append(data, size);
      return true;
    };
    httplib::Result r = client_.send(req);
    if (too_large)
      return HttpResult(HttpError::too_large,
                        "the response is larger than " + std::to_string(max_body_) + " bytes");
    if (!r) return result_of(r);
    return HttpResult(HttpResponse{r->status, std::move(body)});
  }

  // The status alone (the body went to a receiver), or the error.
  static HttpResult result_of(const httplib::Result& r) {
    if (r) return HttpResult(HttpResponse{r->status, {}});
    const httplib::Error e = r.error();
    HttpError kind = HttpError::other;
    if (e == httplib::Error::Connection) kind = HttpError::connection;
    else if (e == httplib::Error::Read) kind = HttpError::read;
    else if (e == httplib::Error::Write) kind = HttpError::write;
    return HttpResult(kind, httplib::to_string(e));
  }

  httplib::Client client_;
  const std::uint64_t max_body_;
};

}  // namespace
}  // namespace rayfarm::cli

extern "C" __attribute__((visibility("default"))) rayfarm::cli::HttpClient* rayfarm_http_client(
    const char* url, const rayfarm::cli::HttpLimits* limits) {
  try {
    return new rayfarm::cli::HttplibClient(url, *limits);
  } catch (...) {
    return nullptr;
  }
}
