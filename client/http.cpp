// Loading the HTTP module (http.h) on first use: beside the program (a build tree), then in
// ../lib/rayfarm (an installed tree: bin/rayfarm, lib/rayfarm/rayfarm-http.so).
#include "http.h"

#include <dlfcn.h>

#include <filesystem>
#include <system_error>

namespace rayfarm::cli {
namespace {

struct Module {
  HttpClientFactory factory = nullptr;
  std::string error;  // why there is no factory
};

const Module& module() {
  static const Module loaded = [] {
    Module m;
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (ec) {
      m.error = "cannot find this program's directory (" + ec.message() + ")";
      return m;
    }
    const std::filesystem::path dir = exe.parent_path();
    std::string tried;
    for (const std::filesystem::path& p :
         {dir / kHttpModuleFile, dir / ".." / "lib" / "rayfarm" / kHttpModuleFile}) {
      if (!std::filesystem::exists(p, ec)) {
        tried += (tried.empty() ? "" : ", ") + p.lexically_normal().string();
        continue;
      }
      void* handle = dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (!handle) {
        const char* why = dlerror();
        m.error = "cannot load " + p.string() + ": " + (why ? why : "unknown error");
        return m;
      }
      m.factory = reinterpret_cast<HttpClientFactory>(dlsym(handle, kHttpModuleEntry));
      if (!m.factory) m.error = p.string() + " has no " + kHttpModuleEntry;
      return m;
    }
    m.error = std::string("the HTTP module ") + kHttpModuleFile +
              " is not installed with this program (looked for " + tried + ")";
    return m;
  }();
  return loaded;
}

// Every request fails, saying why the module is missing.
class Unavailable final : public HttpClient {
 public:
  explicit Unavailable(std::string why) : why_(std::move(why)) {}
  HttpResult get(const std::string&, const HttpHeaders&) override { return fail(); }
  HttpResult get_stream(const std::string&, const HttpHeaders&,
                        const std::function<bool(const char*, std::size_t)>&) override {
    return fail();
  }
  HttpResult post(const std::string&, const HttpHeaders&, const std::string&,
                  const std::string&) override {
    return fail();
  }
  HttpResult post_multipart(const std::string&, const HttpHeaders&,
                            const std::vector<HttpPart>&) override {
    return fail();
  }
  HttpResult del(const std::string&, const HttpHeaders&) override { return fail(); }

 private:
  HttpResult fail() const { return HttpResult(HttpError::unavailable, why_); }
  std::string why_;
};

}  // namespace

std::unique_ptr<HttpClient> http_client(const std::string& url, const HttpLimits& limits) {
  const Module& m = module();
  if (!m.factory) return std::make_unique<Unavailable>(m.error);
  if (HttpClient* c = m.factory(url.c_str(), &limits)) return std::unique_ptr<HttpClient>(c);
  return std::make_unique<Unavailable>("cannot make an HTTP client for " + url);
}

}  // namespace rayfarm::cli
