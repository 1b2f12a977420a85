// rayfarm-http.so: the command line's HTTP client (http.h) over cpp-httplib, built as a module
// that the program loads only when it talks to a server.
#include <httplib.h>

#include "http.h"

namespace rayfarm::cli {
namespace {

HttpResult result_of(const httplib::Result& r) {
  if (r) return HttpResult(HttpResponse{r->status, r->body});
  const httplib::Error e = r.error();
  HttpError kind = HttpError::other;
  if (e == httplib::Error::Connection) kind = HttpError::connection;
  else if (e == httplib::Error::Read) kind = HttpError::read;
  else if (e == httplib::Error::Write) kind = HttpError::write;
  return HttpResult(kind, httplib::to_string(e));
}

httplib::Headers headers_of(const HttpHeaders& h) { return {h.begin(), h.end()}; }

class HttplibClient final : public HttpClient {
 public:
  HttplibClient(const std::string& url, const HttpTimeouts& t) : client_(url) {
    client_.set_connection_timeout(t.connect, 0);
    client_.set_read_timeout(t.read, 0);
    client_.set_write_timeout(t.write, 0);
  }

  HttpResult get(const std::string& path, const HttpHeaders& headers) override {
    return result_of(client_.Get(path, headers_of(headers)));
  }

  HttpResult get_stream(const std::string& path, const HttpHeaders& headers,
                        const std::function<bool(const char*, std::size_t)>& on_data) override {
    return result_of(client_.Get(
        path, headers_of(headers), [](const httplib::Response& r) { return r.status == 200; },
        [&on_data](const char* data, std::size_t size) { return on_data(data, size); }));
  }

  HttpResult post(const std::string& path, const HttpHeaders& headers, const std::string& body,
                  const std::string& content_type) override {
    return result_of(client_.Post(path, headers_of(headers), body, content_type));
  }

  HttpResult post_multipart(const std::string& path, const HttpHeaders& headers,
                            const std::vector<HttpPart>& parts) override {
    httplib::MultipartFormDataItems items;
    for (const HttpPart& p : parts) items.push_back({p.name, p.content, p.filename, p.content_type});
    return result_of(client_.Post(path, headers_of(headers), items));
  }

  HttpResult del(const std::string& path, const HttpHeaders& headers) override {
    return result_of(client_.Delete(path, headers_of(headers)));
  }

 private:
  httplib::Client client_;
};

}  // namespace
}  // namespace rayfarm::cli

extern "C" __attribute__((visibility("default"))) rayfarm::cli::HttpClient* rayfarm_http_client(
    const char* url, const rayfarm::cli::HttpTimeouts* timeouts) {
  try {
    return new rayfarm::cli::HttplibClient(url, *timeouts);
  } catch (...) {
    return nullptr;
  }
}
