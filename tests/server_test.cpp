// rayfarmd in-process: the real Service and HttpApi on a free loopback port, driven by
// httplib::Client for the API (docs/http-api.md) and by raw socket bytes for the cpp-httplib 0.11.4
// weaknesses the server closes (docs/reliability.md), so each stays closed.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "http_api.h"
#include "job_record.h"
#include "rayfarm/compare.h"
#include "rayfarm/image_io.h"
#include "rayfarm/load.h"
#include "rayfarm/render.h"
#include "rayfarm/sha256.h"
#include "service.h"
#include "temp_dir.h"

namespace rayfarm::server {
namespace {

using Json = nlohmann::json;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

// rayfarmd's command line, as main() reads it.
std::optional<Settings> parse_flags(std::vector<std::string> args, int& code) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return parse_settings(static_cast<int>(argv.size()), argv.data(), code);
}

// A write to a socket the server has closed must fail, not kill the test process.
const bool kSigpipeIgnored = [] {
  std::signal(SIGPIPE, SIG_IGN);
  return true;
}();

// The lecture scene, small: one mirror sphere, a floor, one light.
constexpr const char* kScene = R"(# a small test scene
camera cam1
{
   pixeldim  40 30
   worlddim  8 6
   viewpoint 4 3 5
}
material chrome
{  ambient  3 3 3
   diffuse  .1 .1 .1
   specular .9 .9 .9
}
material floor
{  ambient  2 2 2
   diffuse  .5 .5 .5
}
light top
{  location   2.56 3.80 -1.5
   emissivity 4 4 4
}
sphere left
{  material chrome
   center   1.25 .75 -4
   radius   .9
}
plane ground
{  material floor
   normal   0 1 0
   point    0 -0.2 0
}
)";

// The same scene as JSON (its twin: same names, same values).
std::string scene_json() {
  return R"({
  "cameras":   {"cam1": {"pixeldim": [40, 30], "worlddim": [8, 6], "viewpoint": [4, 3, 5]}},
  "materials": {"chrome": {"ambient": [3, 3, 3], "diffuse": [0.1, 0.1, 0.1],
                           "specular": [0.9, 0.9, 0.9]},
                "floor":  {"ambient": [2, 2, 2], "diffuse": [0.5, 0.5, 0.5]}},
  "lights":    [{"name": "top", "location": [2.56, 3.8, -1.5], "emissivity": [4, 4, 4]}],
  "objects":   [{"type": "sphere", "name": "left", "material": "chrome",
                 "center": [1.25, 0.75, -4], "radius": 0.9},
                {"type": "plane", "name": "ground", "material": "floor",
                 "normal": [0, 1, 0], "point": [0, -0.2, 0]}]
})";
}

// Runs about a minute on two workers: for tests that need a job in flight (always canceled).
constexpr const char* kLong = "width=800&height=600&spp=1024";

Settings test_settings() {
  Settings s;
  s.workers = 2;
  s.http_threads = 16;
  s.samples_dir = RAYFARM_SOURCE_DIR "/scenes";
  s.access_log = false;
  s.shutdown_grace = 0;
  return s;
}

// The server on 127.0.0.1:<free port>, listening on its own thread until stop().
class TestServer {
 public:
  explicit TestServer(Settings settings = test_settings(),
                      const std::function<void(httplib::Server&)>& extra_routes = {}) {
    service_ = std::make_unique<Service>(std::move(settings));
    api_ = std::make_unique<HttpApi>(*service_);
    if (extra_routes) extra_routes(api_->http());
    port_ = api_->bind("127.0.0.1", 0);
    if (port_ <= 0) throw std::runtime_error("cannot bind a loopback port");
    thread_ = std::thread([this] { api_->listen(); });
    auto deadline = Clock::now() + 5s;
    while (!api_->http().is_running() && Clock::now() < deadline) std::this_thread::sleep_for(1ms);
    if (!api_->http().is_running()) throw std::runtime_error("the server did not start");
  }
  TestServer(const TestServer&) = delete;
  ~TestServer() { stop(); }

  void stop() {
    if (!api_) return;
    service_->shutdown();
    api_->stop();
    thread_.join();
    api_.reset();
    service_.reset();
  }

  int port() const { return port_; }
  Service& service() { return *service_; }

  std::unique_ptr<httplib::Client> client(const std::string& token = "") const {
    auto c = std::make_unique<httplib::Client>("127.0.0.1", port_);
    c->set_connection_timeout(5);
    c->set_read_timeout(60);
    c->set_write_timeout(10);
    if (!token.empty()) c->set_bearer_token_auth(token);
    return c;
  }

 private:
  std::unique_ptr<Service> service_;
  std::unique_ptr<HttpApi> api_;
  std::thread thread_;
  int port_ = 0;
};

int code_of(const httplib::Result& r) { return r ? r->status : -1; }

Json json_of(const httplib::Result& r) {
  if (!r) return Json();
  return Json::parse(r->body, nullptr, false);
}

std::string query(const std::string& path, const std::string& q) {
  return q.empty() ? path : path + "?" + q;
}

// Submits and returns the new job's id (empty, with a failure, when not accepted).
std::string submit(httplib::Client& c, const std::string& q = "", const std::string& body = kScene) {
  auto r = c.Post(query("/render", q), body, "text/plain");
  EXPECT_TRUE(r);
  if (!r) return {};
  EXPECT_EQ(r->status, 202) << r->body;
  return json_of(r).value("id", "");
}

Json status_of(httplib::Client& c, const std::string& id) {
  auto r = c.Get("/jobs/" + id);
  EXPECT_TRUE(r && r->status == 200);
  return json_of(r);
}

// Polls the job until `done(status)` or the timeout; returns the last status.
Json wait_for(httplib::Client& c, const std::string& id, const std::function<bool(const Json&)>& done,
              std::chrono::milliseconds timeout = 60s) {
  auto deadline = Clock::now() + timeout;
  Json st;
  for (;;) {
    st = status_of(c, id);
    if (st.is_discarded() || st.is_null() || done(st) || Clock::now() >= deadline) return st;
    std::this_thread::sleep_for(5ms);
  }
}

bool is_final_state(const Json& st) {
  std::string s = st.value("state", "");
  return s == "done" || s == "failed" || s == "canceled";
}

Json wait_final(httplib::Client& c, const std::string& id, std::chrono::milliseconds timeout = 60s) {
  return wait_for(c, id, is_final_state, timeout);
}

Json wait_running(httplib::Client& c, const std::string& id) {
  return wait_for(c, id, [](const Json& st) { return st.value("state", "") != "queued"; }, 30s);
}

Scene load_or_fail(const std::string& text, const ResourceResolver* textures = nullptr) {
  LoadedScene loaded = load_scene(text, LoadDetail::full, textures);
  EXPECT_TRUE(loaded.scene.has_value());
  return loaded.scene ? *loaded.scene : Scene{};
}

// What `rayfarm render` writes for this scene and these options: the reference bytes.
std::string local_render(const std::string& text, const std::vector<std::pair<std::string, std::string>>& opts,
                         ImageFormat format = ImageFormat::png,
                         const ResourceResolver* textures = nullptr) {
  Scene scene = load_or_fail(text, textures);
  RenderOptions options;
  for (auto& [k, v] : opts) EXPECT_EQ(apply_option(options, k, v), std::nullopt) << k;
  std::string error;
  Image image = render_image(scene, options, 2, nullptr, {}, nullptr, &error);
  EXPECT_EQ(error, "");
  auto bytes = encode_image(image, format);
  return std::string(bytes.begin(), bytes.end());
}

Image decode_or_fail(const std::string& bytes) {
  std::string error;
  auto image = decode_image(bytes, &error);
  EXPECT_TRUE(image.has_value()) << error;
  return image ? *image : Image{};
}

std::string png_bytes(const Image& image) {
  auto bytes = encode_png(image);
  return std::string(bytes.begin(), bytes.end());
}

Json error_of(const httplib::Result& r) {
  Json j = json_of(r);
  return j.is_object() && j.contains("error") ? j["error"] : Json();
}

// ---- A raw HTTP/1.1 connection: exactly the bytes a test writes --------------------------

struct RawResponse {
  int status = 0;
  std::multimap<std::string, std::string> headers;  // names lower-cased
  std::string body;
  bool has(const std::string& name) const { return headers.count(name) > 0; }
  std::string header(const std::string& name) const {
    auto it = headers.find(name);
    return it == headers.end() ? "" : it->second;
  }
};

class RawConnection {
 public:
  explicit RawConnection(int port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (fd_ < 0 || ::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0)
      throw std::runtime_error("cannot connect");
  }
  RawConnection(const RawConnection&) = delete;
  ~RawConnection() { ::close(fd_); }

  // Writes all bytes or fails (peer closed, reset, or no progress for `timeout`).
  bool send(std::string_view bytes, std::chrono::milliseconds timeout = 2s) {
    size_t done = 0;
    while (done < bytes.size()) {
      pollfd p{fd_, POLLOUT, 0};
      if (::poll(&p, 1, static_cast<int>(timeout.count())) <= 0) return false;
      ssize_t n = ::send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      done += static_cast<size_t>(n);
    }
    return true;
  }

  // One response: status line, headers, and a Content-Length body. nullopt on EOF, reset or
  // timeout before a whole response arrived.
  std::optional<RawResponse> read_response(std::chrono::milliseconds timeout = 5s) {
    auto deadline = Clock::now() + timeout;
    size_t end;
    while ((end = buffer_.find("\r\n\r\n")) == std::string::npos)
      if (!fill(deadline)) return std::nullopt;
    RawResponse res;
    std::string head = buffer_.substr(0, end + 2);
    buffer_.erase(0, end + 4);
    size_t eol = head.find("\r\n");
    std::string status_line = head.substr(0, eol);
    if (status_line.rfind("HTTP/1.", 0) != 0 || status_line.size() < 12) return std::nullopt;
    res.status = std::atoi(status_line.c_str() + 9);
    for (size_t pos = eol + 2; pos < head.size();) {
      size_t next = head.find("\r\n", pos);
      std::string line = head.substr(pos, next - pos);
      pos = next + 2;
      size_t colon = line.find(':');
      if (colon == std::string::npos) continue;
      std::string name = line.substr(0, colon);
      for (char& ch : name) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      std::string value = line.substr(colon + 1);
      while (!value.empty() && value.front() == ' ') value.erase(0, 1);
      res.headers.emplace(name, value);
    }
    size_t length = res.has("content-length") ? std::stoul(res.header("content-length")) : 0;
    while (buffer_.size() < length)
      if (!fill(deadline)) return std::nullopt;
    res.body = buffer_.substr(0, length);
    buffer_.erase(0, length);
    return res;
  }

  // True when the server ends the connection (EOF or reset) within `timeout`; any bytes it
  // sends before that are appended to `extra`.
  bool closed_by_peer(std::chrono::milliseconds timeout, std::string* extra = nullptr) {
    auto deadline = Clock::now() + timeout;
    for (;;) {
      int left = static_cast<int>(
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count());
      if (left <= 0) return false;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, left) <= 0) return false;
      char buf[4096];
      ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return true;
      if (extra) extra->append(buf, static_cast<size_t>(n));
    }
  }

 private:
  bool fill(Clock::time_point deadline) {
    int left = static_cast<int>(
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count());
    if (left <= 0) return false;
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, left) <= 0) return false;
    char buf[16384];
    ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    if (n <= 0) return false;
    buffer_.append(buf, static_cast<size_t>(n));
    return true;
  }

  int fd_ = -1;
  std::string buffer_;
};

std::string scene_post(const std::string& extra_headers, const std::string& body,
                       const std::string& path = "/render") {
  return "POST " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\n" + extra_headers +
         "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body;
}

// ---- POST /render ------------------------------------------------------------------------

TEST(ServerRender, ModelBodyIsAcceptedWithLocationAndLinks) {
  TestServer server;
  auto c = server.client();
  auto r = c->Post("/render", kScene, "text/plain");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 202);
  Json j = json_of(r);
  std::string id = j.value("id", "");
  EXPECT_EQ(id.size(), 32u);
  EXPECT_EQ(r->get_header_value("Location"), "/jobs/" + id);
  EXPECT_TRUE(j.contains("state"));
  EXPECT_TRUE(j["queue_position"].is_number_integer());
  EXPECT_EQ(j["links"]["self"], "/jobs/" + id);
  EXPECT_EQ(j["links"]["image"], "/jobs/" + id + "/image");
  EXPECT_EQ(j["links"]["events"], "/jobs/" + id + "/events");
  EXPECT_EQ(wait_final(*c, id)["state"], "done");
}

TEST(ServerRender, JsonBodyIsAcceptedAndRendersLikeTheModelFile) {
  TestServer server;
  auto c = server.client();
  auto r = c->Post("/render?wait=1", scene_json(), "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->body, local_render(kScene, {}));
}

TEST(ServerRender, MultipartScenePartIsAccepted) {
  TestServer server;
  auto c = server.client();
  httplib::MultipartFormDataItems items = {{"scene", kScene, "scene.txt", "text/plain"}};
  auto r = c->Post("/render?wait=1&spp=2", items);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->body, local_render(kScene, {{"spp", "2"}}));

  // Media types in any case (RFC 9110 §8.3.1); the boundary as sent.
  const std::string body = "--XyZ\r\nContent-Disposition: form-data; name=\"scene\"; "
                           "filename=\"s.txt\"\r\n\r\n" + std::string(kScene) + "\r\n--XyZ--\r\n";
  auto cased = c->Post("/render?wait=1&spp=2", body, "Multipart/Form-Data; boundary=XyZ");
  ASSERT_TRUE(cased);
  EXPECT_EQ(cased->status, 200) << cased->body;
  auto identity = c->Post("/check", {{"Content-Encoding", "Identity"}}, kScene, "text/plain");
  ASSERT_TRUE(identity);
  EXPECT_EQ(identity->status, 200) << identity->body;
  auto page = c->Get("/", {{"Accept", "TEXT/HTML"}});
  ASSERT_TRUE(page);
  EXPECT_EQ(page->get_header_value("Content-Type"), "text/html; charset=utf-8");
  // A weight of 0 is "not acceptable" (RFC 9110 §12.4.2): the route list, not the page.
  for (const char* accept : {"text/html;q=0, application/json", "text/html; q=0.000",
                             "application/json, text/html ;q=0"}) {
    auto list = c->Get("/", {{"Accept", accept}});
    ASSERT_TRUE(list);
    EXPECT_EQ(list->get_header_value("Content-Type"), "application/json") << accept;
  }
  auto weighed = c->Get("/", {{"Accept", "application/json;q=0.5, text/html;q=0.1"}});
  ASSERT_TRUE(weighed);
  EXPECT_EQ(weighed->get_header_value("Content-Type"), "text/html; charset=utf-8");

  httplib::MultipartFormDataItems wrong = {{"model", kScene, "scene.txt", "text/plain"}};
  auto bad = c->Post("/render", wrong);
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  EXPECT_EQ(error_of(bad)["code"], "missing_scene");
}

TEST(ServerRender, BundledSampleRendersByName) {
  TestServer server;
  auto c = server.client();
  auto r = c->Post("/render?sample=cho&width=80&height=60&wait=1");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "image/png");
  Image image = decode_or_fail(r->body);
  EXPECT_EQ(image.width, 80);
  EXPECT_EQ(image.height, 60);

  auto unknown = c->Post("/render?sample=no_such_scene");
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->status, 404);
  EXPECT_EQ(error_of(unknown)["code"], "unknown_sample");
  EXPECT_NE(error_of(unknown)["message"].get<std::string>().find("cho"), std::string::npos);

  // A sample and a scene of one's own: which was meant? Neither is silently dropped.
  auto both = c->Post("/render?sample=cho", kScene, "text/plain");
  ASSERT_TRUE(both);
  EXPECT_EQ(both->status, 400);
  EXPECT_NE(error_of(both)["message"].get<std::string>().find("one or the other"),
            std::string::npos);
}

TEST(ServerRender, EmptyBodyIs400) {
  TestServer server;
  auto c = server.client();
  for (const std::string body : {"", "  \n\t\r\n"}) {
    auto r = c->Post("/render", body, "text/plain");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400);
    EXPECT_EQ(error_of(r)["code"], "empty_scene");
  }
}

TEST(ServerRender, SceneErrorsAre400WithPlaceAndEveryError) {
  TestServer server;
  auto c = server.client();
  const std::string bad = "camera c\n{ pixeldim 40 30\n  worlddim 8 6\n  viewpoint 4 3 5 }\n"
                          "sphere s\n{ material nope\n  center 0 0 -4\n  radious 1 }\n";
  auto r = c->Post("/render", bad, "text/plain");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  Json e = error_of(r);
  EXPECT_EQ(e["code"], "invalid_scene");
  EXPECT_GT(e.value("line", 0), 0);
  EXPECT_GT(e.value("column", 0), 0);
  ASSERT_TRUE(e["errors"].is_array());
  EXPECT_GE(e["errors"].size(), 2u);  // the misspelt attribute and the undefined material
  bool suggested = false;
  for (const Json& item : e["errors"]) {
    EXPECT_TRUE(item.contains("message"));
    suggested |= item["message"].get<std::string>().find("radius") != std::string::npos;
  }
  EXPECT_TRUE(suggested) << e.dump();

  auto json = c->Post("/render", "{\"camera\": [1, 2,", "application/json");
  ASSERT_TRUE(json);
  EXPECT_EQ(json->status, 400);
  EXPECT_EQ(error_of(json)["code"], "invalid_scene");
}

TEST(ServerRender, BadOptionIs400) {
  TestServer server;
  auto c = server.client();
  for (const char* q : {"spp=abc", "spp=0", "highlight=shiny", "no_such_option=1", "camera=nope"}) {
    auto r = c->Post(query("/render", q), kScene, "text/plain");
    ASSERT_TRUE(r) << q;
    EXPECT_EQ(r->status, 400) << q << ": " << r->body;
    EXPECT_EQ(error_of(r)["code"], "invalid_option") << q;
  }
}

TEST(ServerRender, InputThatIsNotUtf8IsA400NotA500) {
  TestServer server;
  auto c = server.client();
  auto camera = c->Post("/render?camera=%FF%FE", kScene, "text/plain");
  ASSERT_TRUE(camera);
  EXPECT_EQ(camera->status, 400) << camera->body;
  EXPECT_EQ(error_of(camera)["code"], "invalid_option");
  std::string bad_scene = std::string(kScene) + "\xff\xfe\xfd { }\n";
  auto scene = c->Post("/render", bad_scene, "text/plain");
  ASSERT_TRUE(scene);
  EXPECT_EQ(scene->status, 400) << scene->body;
  EXPECT_EQ(error_of(scene)["code"], "invalid_scene");
  auto json = c->Post("/render", "{\"cameras\": {\"\xff\": {}}}", "application/json");
  ASSERT_TRUE(json);
  EXPECT_EQ(json->status, 400) << json->body;
}

TEST(ServerRender, EachLimitIs422AndNamed) {
  Settings s = test_settings();
  s.max_pixels = 10000;
  s.max_spp = 16;
  s.max_depth = 10;
  s.max_objects = 1;
  TestServer server(s);
  auto c = server.client();
  const std::string one_object = "camera c { pixeldim 40 30 worlddim 8 6 viewpoint 4 3 5 }\n"
                                 "material m { diffuse 1 }\n"
                                 "sphere s { material m center 4 3 -4 radius 1 }\n";
  struct Case {
    std::string query, body, limit;
  } cases[] = {{"width=200&height=100", one_object, "max_pixels"},
               {"spp=17", one_object, "max_spp"},
               {"max_depth=11", one_object, "max_depth"},
               {"", kScene, "max_objects"}};
  for (const Case& k : cases) {
    auto r = c->Post(query("/render", k.query), k.body, "text/plain");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 422) << k.limit;
    EXPECT_EQ(error_of(r)["limit"], k.limit);
    EXPECT_EQ(error_of(r)["code"], "limit_exceeded");
  }
  auto ok = c->Post("/render?spp=16&max_depth=10", one_object, "text/plain");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 202);
}

TEST(ServerRender, WaitAnswersTheCliBytesWithHeaders) {
  TestServer server;
  auto c = server.client();
  auto r = c->Post("/render?wait=1&spp=4&seed=7&highlight=blinn", kScene, "text/plain");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(r->get_header_value("X-Job-Id").size(), 32u);
  EXPECT_FALSE(r->get_header_value("X-Render-Ms").empty());
  EXPECT_EQ(r->get_header_value("X-Cache"), "miss");
  EXPECT_FALSE(r->get_header_value("ETag").empty());
  EXPECT_EQ(r->body, local_render(kScene, {{"spp", "4"}, {"seed", "7"}, {"highlight", "blinn"}}));
  // A POST is never answered 304, whatever its If-None-Match: its image is what it waited for.
  auto again = c->Post("/render?wait=1&spp=4&seed=7&highlight=blinn",
                       {{"If-None-Match", r->get_header_value("ETag")}}, kScene, "text/plain");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 200);
  EXPECT_EQ(again->body, r->body);

  auto ppm = c->Post("/render?wait=1&format=ppm", kScene, "text/plain");
  ASSERT_TRUE(ppm);
  ASSERT_EQ(ppm->status, 200);
  EXPECT_EQ(ppm->get_header_value("Content-Type"), "image/x-portable-pixmap");
  EXPECT_EQ(ppm->body, local_render(kScene, {}, ImageFormat::ppm));
}

TEST(ServerRender, BodyOverTheLimitIs413) {
  Settings s = test_settings();
  s.max_body_bytes = 64 * 1024;
  TestServer server(s);
  auto c = server.client();
  std::string big = std::string(kScene) + "#" + std::string(70 * 1024, 'x') + "\n";
  auto r = c->Post("/render", big, "text/plain");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 413);
  EXPECT_EQ(error_of(r)["limit"], "max_body_bytes");
  auto ok = c->Post("/render", std::string(kScene) + "#" + std::string(30 * 1024, 'x') + "\n",
                    "text/plain");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 202);
}

TEST(ServerQueue, FullQueueIs429WithRetryAfter) {
  Settings s = test_settings();
  s.queue_capacity = 1;
  TestServer server(s);
  auto c = server.client();
  std::string slow = submit(*c, kLong);
  auto r = c->Post("/render", kScene, "text/plain");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 429);
  EXPECT_EQ(error_of(r)["code"], "queue_full");
  EXPECT_GT(std::atoi(r->get_header_value("Retry-After").c_str()), 0);
  // Room again once the slow job is canceled.
  ASSERT_EQ(code_of(c->Delete("/jobs/" + slow)), 200);
  EXPECT_EQ(wait_final(*c, slow)["state"], "canceled");
  EXPECT_EQ(code_of(c->Post("/render", kScene, "text/plain")), 202);
}

TEST(ServerQueue, OneClientCannotHoldMoreThanItsShare) {
  Settings s = test_settings();
  s.max_jobs_per_client = 2;
  TestServer server(s);
  auto alice = server.client("alice");
  std::string a = submit(*alice, kLong), b = submit(*alice, kLong);
  auto r = alice->Post("/render", kScene, "text/plain");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 429);
  EXPECT_EQ(error_of(r)["code"], "too_many_jobs");
  EXPECT_FALSE(r->get_header_value("Retry-After").empty());
  EXPECT_EQ(code_of(server.client("bob")->Post("/render", kScene, "text/plain")), 202);
  alice->Delete("/jobs/" + a);
  alice->Delete("/jobs/" + b);
}

// ---- /jobs -------------------------------------------------------------------------------

TEST(ServerJobs, UnknownJobIs404) {
  TestServer server;
  auto c = server.client();
  for (const char* path : {"/jobs/0123456789abcdef0123456789abcdef", "/jobs/nope",
                           "/jobs/0123456789abcdef0123456789abcdef/image",
                           "/jobs/0123456789abcdef0123456789abcdef/events"}) {
    auto r = c->Get(path);
    ASSERT_TRUE(r) << path;
    EXPECT_EQ(r->status, 404) << path;
    EXPECT_EQ(error_of(r)["code"], "not_found") << path;
  }
  auto del = c->Delete("/jobs/0123456789abcdef0123456789abcdef");
  ASSERT_TRUE(del);
  EXPECT_EQ(del->status, 404);
}

TEST(ServerJobs, StatusHasTheSpecFields) {
  TestServer server;
  auto c = server.client();
  std::string id = submit(*c, "spp=3");
  Json st = wait_final(*c, id);
  EXPECT_EQ(st["state"], "done");
  EXPECT_EQ(st["progress"], 1.0);
  EXPECT_EQ(st["queue_position"], 0);
  for (const char* key : {"created_at", "started_at", "finished_at"})
    EXPECT_TRUE(st[key].is_string()) << key;
  EXPECT_TRUE(st["elapsed_ms"].is_number());
  EXPECT_TRUE(st.contains("eta_ms"));
  EXPECT_EQ(st["spp_done"], 3);
  EXPECT_TRUE(st["error_estimate"].is_number());
  EXPECT_GT(st["stats"]["rays"]["primary"].get<long long>(), 0);
  EXPECT_TRUE(st["stats"]["rays"].contains("shadow"));
  EXPECT_TRUE(st["stats"]["rays"].contains("reflection"));
  EXPECT_TRUE(st["stats"].contains("rays_per_second"));
  EXPECT_TRUE(st["stats"]["parts"].is_array());
  EXPECT_EQ(st["options"]["spp"], 3);  // typed, as in a JSON scene
  EXPECT_EQ(st["options"]["shadows"], true);
  EXPECT_EQ(st["options"]["background"], Json::array({0, 0, 0}));
  EXPECT_TRUE(st["error"].is_null());
}

TEST(ServerJobs, ListShowsOnlyTheCallersJobs) {
  TestServer server;
  auto alice = server.client("alice-token");
  auto bob = server.client("bob-token");
  std::string a1 = submit(*alice), a2 = submit(*alice, "spp=2"), b1 = submit(*bob);
  auto ids = [](httplib::Client& c) {
    auto r = c.Get("/jobs");
    EXPECT_TRUE(r && r->status == 200);
    std::vector<std::string> out;
    Json list = json_of(r);
    for (const Json& j : list["jobs"]) out.push_back(j["id"]);
    return out;
  };
  EXPECT_EQ(ids(*alice), (std::vector<std::string>{a2, a1}));  // newest first
  EXPECT_EQ(ids(*bob), (std::vector<std::string>{b1}));
  EXPECT_TRUE(ids(*server.client()).empty());
}

TEST(ServerJobs, ImageIs409WhileRunningAndPartialShowsProgress) {
  TestServer server;
  auto c = server.client();
  std::string id = submit(*c, kLong);
  Json st = wait_running(*c, id);
  ASSERT_EQ(st["state"], "running");
  auto r = c->Get("/jobs/" + id + "/image");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 409);
  EXPECT_EQ(json_of(r)["id"], id);  // the status document
  EXPECT_EQ(error_of(r)["code"], "not_done");  // in the documented error shape
  EXPECT_EQ(r->get_header_value("Retry-After"), "1");

  auto partial = c->Get("/jobs/" + id + "/image?partial=1");
  ASSERT_TRUE(partial);
  ASSERT_EQ(partial->status, 200);
  EXPECT_EQ(partial->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(partial->get_header_value("X-Job-State"), "running");
  EXPECT_EQ(partial->get_header_value("Cache-Control"), "no-store");  // it grows as tiles finish
  Image image = decode_or_fail(partial->body);
  EXPECT_EQ(image.width, 800);
  EXPECT_EQ(image.height, 600);

  auto ppm = c->Get("/jobs/" + id + "/image?partial=1&format=ppm");
  ASSERT_TRUE(ppm);
  EXPECT_EQ(ppm->body.substr(0, 2), "P6");
  // Some tiles rendered, then canceled: the partial image keeps them (it was all black).
  wait_for(*c, id, [](const Json& s) { return s["progress"].get<double>() > 0.05; });
  auto del = c->Delete("/jobs/" + id);
  ASSERT_TRUE(del);
  ASSERT_EQ(del->status, 200);
  EXPECT_EQ(json_of(del)["state"], "canceled");  // the state after the cancel
  const Json final_status = wait_final(*c, id);
  ASSERT_EQ(final_status["state"], "canceled");
  auto kept = c->Get("/jobs/" + id + "/image?partial=1");
  ASSERT_TRUE(kept);
  ASSERT_EQ(kept->status, 200);
  EXPECT_EQ(kept->get_header_value("X-Job-State"), "canceled");
  const Image so_far = decode_or_fail(kept->body);
  EXPECT_TRUE(std::any_of(so_far.rgb.begin(), so_far.rgb.end(), [](std::uint8_t v) { return v > 0; }));
}

TEST(ServerJobs, DoneImageIsPngOrPpmAndRevalidates) {
  TestServer server;
  auto c = server.client();
  std::string id = submit(*c, "spp=2");
  ASSERT_EQ(wait_final(*c, id)["state"], "done");
  auto r = c->Get("/jobs/" + id + "/image");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  EXPECT_EQ(r->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(r->body, local_render(kScene, {{"spp", "2"}}));
  std::string etag = r->get_header_value("ETag");
  ASSERT_FALSE(etag.empty());

  auto again = c->Get("/jobs/" + id + "/image", {{"If-None-Match", etag}});
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 304);
  EXPECT_TRUE(again->body.empty());
  // No "Content-Length: 0": a 304 may only give the image's own length (RFC 9110 §8.6).
  EXPECT_FALSE(again->has_header("Content-Length"));
  EXPECT_EQ(again->get_header_value("ETag"), etag);
  // RFC 9110's other forms: a list, a weak tag, any representation; another tag is no match.
  for (const std::string& header : {"\"other\", " + etag, "W/" + etag, std::string("*")}) {
    auto listed = c->Get("/jobs/" + id + "/image", {{"If-None-Match", header}});
    ASSERT_TRUE(listed);
    EXPECT_EQ(listed->status, 304) << header;
  }
  auto other = c->Get("/jobs/" + id + "/image", {{"If-None-Match", "\"other\""}});
  ASSERT_TRUE(other);
  EXPECT_EQ(other->status, 200);
  // Repeated header lines are one list.
  auto lines = c->Get("/jobs/" + id + "/image",
                      {{"If-None-Match", "\"other\""}, {"If-None-Match", etag}});
  ASSERT_TRUE(lines);
  EXPECT_EQ(lines->status, 304);

  auto ppm = c->Get("/jobs/" + id + "/image?format=ppm");
  ASSERT_TRUE(ppm);
  ASSERT_EQ(ppm->status, 200);
  EXPECT_EQ(ppm->get_header_value("Content-Type"), "image/x-portable-pixmap");
  EXPECT_EQ(ppm->body, local_render(kScene, {{"spp", "2"}}, ImageFormat::ppm));
  EXPECT_NE(ppm->get_header_value("ETag"), etag);  // another representation
}

TEST(ServerJobs, DeleteStopsARunningJobWithinASecond) {
  TestServer server;
  auto c = server.client();
  std::string id = submit(*c, kLong);
  ASSERT_EQ(wait_running(*c, id)["state"], "running");
  std::this_thread::sleep_for(100ms);  // well into rendering
  auto start = Clock::now();
  auto r = c->Delete("/jobs/" + id);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  Json st = wait_final(*c, id, 5s);
  auto took = Clock::now() - start;
  EXPECT_EQ(st["state"], "canceled");
  EXPECT_LT(took, 1s);
  EXPECT_LT(st["progress"].get<double>(), 0.5);

  auto image = c->Get("/jobs/" + id + "/image");
  ASSERT_TRUE(image);
  EXPECT_EQ(image->status, 410);
  EXPECT_EQ(error_of(image)["code"], "canceled");
  EXPECT_EQ(code_of(c->Delete("/jobs/" + id)), 200);  // canceling twice is fine
}

TEST(ServerJobs, DeleteOfAQueuedJobCancelsIt) {
  Settings s = test_settings();
  s.workers = 1;
  TestServer server(s);
  auto c = server.client("alice");
  auto other = server.client("bob");
  std::string first = submit(*other, kLong);
  ASSERT_EQ(wait_running(*other, first)["state"], "running");
  // Five of one client: the fifth waits (a client runs at most four jobs at once).
  std::vector<std::string> ids;
  for (int i = 1; i <= 5; ++i)
    ids.push_back(submit(*c, kLong + std::string("&seed=") + std::to_string(i)));
  Json st = status_of(*c, ids.back());
  ASSERT_EQ(st["state"], "queued");
  EXPECT_GT(st["queue_position"].get<int>(), 0);
  ASSERT_EQ(code_of(c->Delete("/jobs/" + ids.back())), 200);
  EXPECT_EQ(status_of(*c, ids.back())["state"], "canceled");
  for (auto& id : ids) c->Delete("/jobs/" + id);
  other->Delete("/jobs/" + first);
}

TEST(ServerJobs, OnlyTheSubmitterMayCancel) {
  TestServer server;
  auto alice = server.client("alice-token");
  auto bob = server.client("bob-token");
  std::string id = submit(*alice, kLong);
  auto r = bob->Delete("/jobs/" + id);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 403);
  EXPECT_NE(status_of(*alice, id)["state"], "canceled");
  EXPECT_EQ(code_of(alice->Delete("/jobs/" + id)), 200);
  EXPECT_EQ(wait_final(*alice, id)["state"], "canceled");

  std::string done = submit(*alice);
  ASSERT_EQ(wait_final(*alice, done)["state"], "done");
  auto late = alice->Delete("/jobs/" + done);
  ASSERT_TRUE(late);
  EXPECT_EQ(late->status, 409);
}

// ---- Fair sharing ------------------------------------------------------------------------

void small_job_overtakes_big_job(const std::string& big_client, const std::string& small_client) {
  TestServer server;
  auto big_c = server.client(big_client);
  auto small_c = server.client(small_client);
  std::string big = submit(*big_c, "width=800&height=600&spp=256");
  ASSERT_EQ(wait_running(*big_c, big)["state"], "running");
  std::string small = submit(*small_c, "spp=2");
  Json small_st = wait_final(*small_c, small, 30s);
  Json big_st = status_of(*big_c, big);
  EXPECT_EQ(small_st["state"], "done");
  EXPECT_EQ(big_st["state"], "running") << "the small job waited for the big one";
  EXPECT_LT(big_st["progress"].get<double>(), 1.0);
  big_c->Delete("/jobs/" + big);
}

TEST(ServerFairness, SmallJobOfAnotherClientFinishesBeforeABigOne) {
  small_job_overtakes_big_job("alice", "bob");
}

TEST(ServerFairness, SmallJobOfTheSameClientFinishesBeforeABigOne) {
  small_job_overtakes_big_job("alice", "alice");
}

// Many one-tile jobs at once: workers constantly pick jobs that another worker is finishing.
TEST(ServerFairness, ManySmallJobsOfManyClientsAllFinish) {
  TestServer server;
  std::vector<std::thread> threads;
  std::atomic<int> done{0};
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      auto c = server.client("client-" + std::to_string(t));
      std::vector<std::string> ids;
      for (int i = 0; i < 15; ++i)
        ids.push_back(submit(*c, "width=16&height=12&spp=3&seed=" + std::to_string(t * 100 + i)));
      for (auto& id : ids) done += wait_final(*c, id, 60s).value("state", "") == "done";
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(done, 60);
}

// ---- Event streams -----------------------------------------------------------------------

struct Event {
  std::string name;
  Json data;
};

std::vector<Event> parse_events(const std::string& text) {
  std::vector<Event> out;
  size_t pos = 0;
  for (size_t end; (end = text.find("\n\n", pos)) != std::string::npos; pos = end + 2) {
    std::string block = text.substr(pos, end - pos);
    Event e;
    std::string data;
    size_t lp = 0;
    while (lp <= block.size()) {
      size_t le = block.find('\n', lp);
      if (le == std::string::npos) le = block.size();
      std::string line = block.substr(lp, le - lp);
      if (line.rfind("event: ", 0) == 0) e.name = line.substr(7);
      if (line.rfind("data: ", 0) == 0) data += line.substr(6);
      lp = le + 1;
    }
    if (e.name.empty()) continue;  // a comment (keep-alive)
    e.data = Json::parse(data, nullptr, false);
    out.push_back(e);
  }
  return out;
}

TEST(ServerEvents, StreamSendsProgressThenDoneAndEnds) {
  TestServer server;
  auto c = server.client();
  std::string id = submit(*c, "width=400&height=300&spp=48");
  std::string text;
  auto start = Clock::now();
  auto r = c->Get("/jobs/" + id + "/events", [&](const char* data, size_t n) {
    text.append(data, n);
    return true;
  });
  ASSERT_TRUE(r) << "the stream did not end";
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(r->get_header_value("Content-Type"), "text/event-stream");
  EXPECT_LT(Clock::now() - start, 60s);
  auto events = parse_events(text);
  ASSERT_GE(events.size(), 2u) << text;
  for (size_t i = 0; i + 1 < events.size(); ++i) EXPECT_EQ(events[i].name, "progress");
  EXPECT_EQ(events.back().name, "done");
  EXPECT_EQ(events.back().data["state"], "done");
  EXPECT_EQ(events.back().data["progress"], 1.0);
  // Progress only grows.
  double last = -1;
  for (auto& e : events) {
    double p = e.data["progress"].get<double>();
    EXPECT_GE(p, last);
    last = p;
  }
}

// A queued job's place moves when a job before it leaves, with no change to its own record:
// the stream says so (it sent the first place only).
TEST(ServerEvents, AQueuedJobsStreamFollowsItsPlace) {
  Settings s = test_settings();
  s.workers = 1;
  TestServer server(s);
  auto c = server.client();
  std::vector<std::string> ids;
  for (int i = 0; i < 6; ++i) ids.push_back(submit(*c, std::string(kLong) + "&seed=" + std::to_string(i)));
  ASSERT_EQ(wait_for(*c, ids[5], [](const Json& st) { return st["queue_position"] == 2; }, 10s)
                ["queue_position"], 2);
  std::mutex mu;
  std::string text;
  std::thread reader([&] {
    server.client()->Get("/jobs/" + ids[5] + "/events", [&](const char* data, size_t n) {
      std::lock_guard lock(mu);
      text.append(data, n);
      return true;
    });
  });
  auto has = [&](const std::string& needle) {
    std::lock_guard lock(mu);
    return text.find(needle) != std::string::npos;
  };
  auto deadline = Clock::now() + 10s;
  while (!has("\"queue_position\":2") && Clock::now() < deadline) std::this_thread::sleep_for(5ms);
  EXPECT_EQ(code_of(c->Delete("/jobs/" + ids[4])), 200);
  deadline = Clock::now() + 10s;
  while (!has("\"queue_position\":1") && Clock::now() < deadline) std::this_thread::sleep_for(5ms);
  EXPECT_TRUE(has("\"queue_position\":1")) << text;
  for (const std::string& id : ids) c->Delete("/jobs/" + id);
  reader.join();
}

TEST(ServerEvents, StreamsOverTheCapAre503AndACancelEndsTheStream) {
  Settings s = test_settings();
  s.max_event_streams = 1;
  TestServer server(s);
  auto c = server.client();
  std::string id = submit(*c, kLong);
  std::mutex mu;
  std::string text;
  std::atomic<bool> ended{false};
  std::thread reader([&] {
    auto rc = server.client();
    rc->Get("/jobs/" + id + "/events", [&](const char* data, size_t n) {
      std::lock_guard lock(mu);
      text.append(data, n);
      return true;
    });
    ended = true;
  });
  auto received = [&] {
    std::lock_guard lock(mu);
    return !text.empty();
  };
  auto deadline = Clock::now() + 10s;
  while (!received() && Clock::now() < deadline) std::this_thread::sleep_for(5ms);
  EXPECT_TRUE(received());
  // The first stream holds the only slot.
  auto r = c->Get("/jobs/" + id + "/events");
  EXPECT_TRUE(r && r->status == 503);
  EXPECT_TRUE(r && !r->get_header_value("Retry-After").empty());
  EXPECT_EQ(code_of(c->Delete("/jobs/" + id)), 200);  // ends the first stream
  reader.join();
  EXPECT_TRUE(ended);
  auto events = parse_events(text);
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back().name, "canceled");
}

// ---- The result cache --------------------------------------------------------------------

TEST(ServerCache, SameSceneAndOptionsAreACacheHit) {
  TestServer server;
  auto c = server.client();
  auto first = c->Post("/render?wait=1&spp=2", kScene, "text/plain");
  ASSERT_TRUE(first);
  ASSERT_EQ(first->status, 200);
  EXPECT_EQ(first->get_header_value("X-Cache"), "miss");
  // Layout and comments do not matter: the scene as parsed is the key.
  std::string relaid = "# another comment\n" + std::string(kScene);
  auto second = c->Post("/render?wait=1&spp=2", relaid, "text/plain");
  ASSERT_TRUE(second);
  ASSERT_EQ(second->status, 200);
  EXPECT_EQ(second->get_header_value("X-Cache"), "hit");
  EXPECT_EQ(second->body, first->body);
  EXPECT_NE(second->get_header_value("X-Job-Id"), first->get_header_value("X-Job-Id"));
  auto other = c->Post("/render?wait=1&spp=3", kScene, "text/plain");
  ASSERT_TRUE(other);
  EXPECT_EQ(other->get_header_value("X-Cache"), "miss");
  auto m = c->Get("/metrics");
  ASSERT_TRUE(m);
  const std::string& metrics = m->body;
  EXPECT_NE(metrics.find("rayfarm_cache_hits_total 1\n"), std::string::npos) << metrics;
}

// ---- Jobs of one image merged while it renders -------------------------------------------

// A counter's value in /metrics (the first line that starts with `name`); -1 when absent.
double metric_value(httplib::Client& c, const std::string& name) {
  auto r = c.Get("/metrics");
  if (!r) return -1;
  std::istringstream lines(r->body);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind(name + " ", 0) == 0) return std::atof(line.c_str() + name.size() + 1);
  return -1;
}

// Some 0.4 s on two workers.
constexpr const char* kMedium = "width=400&height=300&spp=64";

// A class submits one scene at once: it renders once, and every job ends done with the image
// `rayfarm render` writes for it.
TEST(ServerMerge, OneImageSubmittedByAClassRendersOnce) {
  TestServer server;
  std::vector<std::unique_ptr<httplib::Client>> students;
  std::vector<std::string> ids;
  for (int i = 0; i < 12; ++i) {
    students.push_back(server.client("student-" + std::to_string(i)));
    ids.push_back(submit(*students.back(), kMedium));
  }
  const std::string expected =
      local_render(kScene, {{"width", "400"}, {"height", "300"}, {"spp", "64"}});
  int rendered = 0;
  for (int i = 0; i < 12; ++i) {
    const Json st = wait_final(*students[i], ids[i]);
    ASSERT_EQ(st["state"], "done") << st.dump();
    rendered += st["stats"]["cache"] == "miss";
    auto image = students[i]->Get("/jobs/" + ids[i] + "/image");
    ASSERT_TRUE(image);
    ASSERT_EQ(image->status, 200);
    EXPECT_TRUE(image->body == expected) << i;
  }
  EXPECT_EQ(rendered, 1);
  auto c = server.client();
  EXPECT_EQ(metric_value(*c, "rayfarm_jobs_finished_total{state=\"done\"}"), 1);
  // Each of the others either waited for that render or came after it, from the cache.
  EXPECT_EQ(metric_value(*c, "rayfarm_jobs_merged_total") +
                metric_value(*c, "rayfarm_cache_hits_total"),
            11);
}

// A job of an image under way runs with that render and shows its progress; canceled, it
// ends alone. The render's own job canceled hands the render to a job that waited for it. A
// job more urgent than the render under way renders its own.
TEST(ServerMerge, AWaitingJobRunsWithTheRenderAndOutlivesItsCancel) {
  Settings s = test_settings();
  s.workers = 1;
  TestServer server(s);
  auto alice = server.client("alice"), bob = server.client("bob"), carol = server.client("carol"),
       dave = server.client("dave");
  const std::string a = submit(*alice, kLong);
  ASSERT_EQ(wait_running(*alice, a)["state"], "running");
  const std::string b = submit(*bob, kLong);
  EXPECT_EQ(status_of(*bob, b)["state"], "running");
  EXPECT_GT(wait_for(*bob, b, [](const Json& st) { return st["progress"] > 0; }, 10s)["progress"],
            0);
  EXPECT_EQ(metric_value(*bob, "rayfarm_jobs_merged_total"), 1);
  const std::string c = submit(*carol, kLong + std::string("&priority=interactive"));
  EXPECT_EQ(metric_value(*carol, "rayfarm_jobs_merged_total"), 1);  // carol's renders alone
  const std::string d = submit(*dave, kLong + std::string("&priority=batch"));
  EXPECT_EQ(metric_value(*dave, "rayfarm_jobs_merged_total"), 2);

  ASSERT_EQ(code_of(bob->Delete("/jobs/" + b)), 200);
  EXPECT_EQ(wait_final(*bob, b, 5s)["state"], "canceled");
  EXPECT_EQ(status_of(*alice, a)["state"], "running");
  EXPECT_EQ(status_of(*dave, d)["state"], "running");

  // Started with alice's render; once that is canceled, dave's job renders itself from the
  // start (a start of its own).
  const Json with_alice = status_of(*dave, d);
  EXPECT_EQ(with_alice["started_at"], status_of(*alice, a)["started_at"]);
  std::this_thread::sleep_for(5ms);
  ASSERT_EQ(code_of(alice->Delete("/jobs/" + a)), 200);
  EXPECT_EQ(wait_final(*alice, a, 5s)["state"], "canceled");
  const Json now = wait_for(*dave, d, [&](const Json& st) {
    return st["state"] == "running" && st["started_at"] != with_alice["started_at"] &&
           st["stats"]["rays"]["primary"] > 0;
  }, 20s);
  EXPECT_EQ(now["state"], "running") << now.dump();
  EXPECT_NE(now["started_at"], with_alice["started_at"]) << now.dump();
  ASSERT_EQ(code_of(dave->Delete("/jobs/" + d)), 200);
  EXPECT_EQ(wait_final(*dave, d, 5s)["state"], "canceled");
  ASSERT_EQ(code_of(carol->Delete("/jobs/" + c)), 200);
  EXPECT_EQ(wait_final(*carol, c, 5s)["state"], "canceled");
}

// A shutdown puts a render and the jobs waiting for it back in the queue; after the restart
// they wait for one render again.
TEST(ServerMerge, JobsWaitingForARenderWaitAgainAfterARestart) {
  test::TempDir dir;
  Settings s = test_settings();
  s.results_dir = dir.path.string();
  std::string a, b;
  {
    TestServer server(s);
    auto alice = server.client("alice"), bob = server.client("bob");
    a = submit(*alice, kLong);
    ASSERT_EQ(wait_running(*alice, a)["state"], "running");
    b = submit(*bob, kLong);
    ASSERT_EQ(status_of(*bob, b)["state"], "running");
    server.stop();
  }
  TestServer server(s);
  auto alice = server.client("alice"), bob = server.client("bob");
  EXPECT_EQ(wait_running(*alice, a)["state"], "running");
  EXPECT_EQ(wait_running(*bob, b)["state"], "running");
  EXPECT_EQ(metric_value(*alice, "rayfarm_jobs_running"), 1);  // one render for both
  ASSERT_EQ(code_of(bob->Delete("/jobs/" + b)), 200);
  EXPECT_EQ(wait_final(*bob, b, 5s)["state"], "canceled");
  ASSERT_EQ(code_of(alice->Delete("/jobs/" + a)), 200);
  EXPECT_EQ(wait_final(*alice, a, 5s)["state"], "canceled");
}

// A render that fails fails the jobs that waited for it, with its error: the same scene and
// options would fail the same way.
TEST(ServerMerge, AFailedRenderFailsTheJobsThatWaitedForIt) {
  Settings s = test_settings();
  s.job_timeout = 3;  // bob's job comes well within it, on a slow machine too
  TestServer server(s);
  auto alice = server.client("alice"), bob = server.client("bob");
  const std::string a = submit(*alice, kLong);
  const std::string b = submit(*bob, kLong);
  const Json sa = wait_final(*alice, a), sb = wait_final(*bob, b);
  ASSERT_EQ(sa["state"], "failed") << sa.dump();
  ASSERT_EQ(sb["state"], "failed") << sb.dump();
  EXPECT_EQ(sb["error"], sa["error"]);
  EXPECT_EQ(sb["error"]["code"], "timeout");
  EXPECT_EQ(metric_value(*alice, "rayfarm_jobs_merged_total"), 1);
}

TEST(ServerCache, ModelFileAndItsJsonTwinShareAnEntry) {
  TestServer server;
  auto c = server.client();
  auto model = c->Post("/render?wait=1", kScene, "text/plain");
  ASSERT_TRUE(model);
  ASSERT_EQ(model->status, 200);
  auto json = c->Post("/render?wait=1", scene_json(), "application/json");
  ASSERT_TRUE(json);
  ASSERT_EQ(json->status, 200) << json->body;
  EXPECT_EQ(json->get_header_value("X-Cache"), "hit");
  EXPECT_EQ(json->body, model->body);
}

// ---- Profiles ----------------------------------------------------------------------------

struct Rendered {
  std::string cache, key, id, png;
};

Rendered render_waiting(httplib::Client& c, const std::string& q, const std::string& body = kScene,
                        const std::string& type = "text/plain") {
  auto r = c.Post(query("/render", "wait=1" + (q.empty() ? "" : "&" + q)), body, type);
  EXPECT_TRUE(r);
  if (!r) return {};
  EXPECT_EQ(r->status, 200) << r->body;
  return {r->get_header_value("X-Cache"), r->get_header_value("ETag"),
          r->get_header_value("X-Job-Id"), r->body};
}

std::string scene_json_with(const std::string& render) {
  std::string json = scene_json();
  return json.substr(0, json.rfind('}')) + ", \"render\": " + render + "}";
}

// The server's default profile is the profile of a request whose query and scene name none;
// the query wins over the scene's render block, which wins over the server. The key (the
// ETag) follows the effective options, so it is the same on any server.
TEST(ServerProfiles, DefaultProfileAppliesWhenNeitherRequestNorSceneNamesOne) {
  Settings s = test_settings();
  s.default_profile = Profile::cpsc102;
  TestServer course(s);
  TestServer lecture;
  auto c = course.client();
  auto l = lecture.client();

  Rendered plain = render_waiting(*c, "");
  EXPECT_EQ(plain.cache, "miss");
  Json opts = status_of(*c, plain.id)["options"];
  EXPECT_EQ(opts["profile"], "cpsc102");
  EXPECT_EQ(opts["rounding"], "truncate");
  EXPECT_EQ(opts["max_dist"], 20);
  EXPECT_EQ(opts["max_depth"], 64);

  // The lecture profile is another entry, here and on a lecture server.
  Rendered lect = render_waiting(*c, "profile=lecture");
  EXPECT_EQ(lect.cache, "miss");
  EXPECT_NE(lect.key, plain.key);
  opts = status_of(*c, lect.id)["options"];
  EXPECT_EQ(opts["profile"], "lecture");
  EXPECT_EQ(opts["rounding"], "nearest");
  EXPECT_EQ(opts["max_dist"], "unlimited");
  EXPECT_EQ(opts["max_depth"], 8);
  EXPECT_NE(lect.png, plain.png);  // the floor beyond MAX_DIST 20
  EXPECT_EQ(render_waiting(*l, "").key, lect.key);
  EXPECT_EQ(render_waiting(*l, "profile=cpsc102").key, plain.key);

  // The profile's defaults spelled out are the same request.
  Rendered spelled =
      render_waiting(*c, "profile=cpsc102&rounding=truncate&max_dist=20&max_depth=64");
  EXPECT_EQ(spelled.cache, "hit");
  EXPECT_EQ(spelled.key, plain.key);
  EXPECT_EQ(spelled.png, plain.png);
  EXPECT_EQ(render_waiting(*c, "").cache, "hit");

  // The scene's render block over the server's default; the query over both.
  Rendered from_scene =
      render_waiting(*c, "", scene_json_with(R"({"profile": "lecture"})"), "application/json");
  EXPECT_EQ(status_of(*c, from_scene.id)["options"]["profile"], "lecture");
  EXPECT_EQ(from_scene.png, lect.png);
  Rendered from_query = render_waiting(*c, "profile=cpsc102",
                                       scene_json_with(R"({"profile": "lecture"})"),
                                       "application/json");
  EXPECT_EQ(status_of(*c, from_query.id)["options"]["profile"], "cpsc102");
  EXPECT_EQ(from_query.png, plain.png);

  // An option the profile refuses is placed where it was given, whatever gave the profile
  // (this server's default is cpsc102).
  auto refused = [&](const std::string& query, const std::string& body, const char* type) {
    auto r = c->Post("/render?" + query, body, type);
    EXPECT_TRUE(r && r->status == 400) << query << (r ? r->body : "");
    return r ? error_of(r) : Json();
  };
  EXPECT_EQ(refused("seed=4294967296", scene_json(), "application/json")["path"], "seed");
  EXPECT_EQ(refused("profile=cpsc102&precision=float", scene_json(), "application/json")["path"],
            "precision");
  EXPECT_EQ(refused("profile=cpsc102", scene_json_with(R"({"bailout": 0.5})"),
                    "application/json")["path"],
            "/render/bailout");
  // The server's default profile (this one's) with the query's option: the option.
  EXPECT_EQ(refused("highlight=blinn", kScene, "text/plain")["path"], "highlight");
}

TEST(ServerProfiles, DefaultProfileIsAFlagAndAnEnvironmentVariable) {
  int code = 0;
  auto s = parse_flags({"rayfarmd"}, code);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->default_profile, Profile::lecture);
  s = parse_flags({"rayfarmd", "--default-profile", "cpsc102"}, code);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->default_profile, Profile::cpsc102);
  ::setenv("RAYFARM_DEFAULT_PROFILE", "cpsc102", 1);
  s = parse_flags({"rayfarmd"}, code);
  ::unsetenv("RAYFARM_DEFAULT_PROFILE");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->default_profile, Profile::cpsc102);
  EXPECT_FALSE(parse_flags({"rayfarmd", "--default-profile", "cpsc101"}, code));
  EXPECT_EQ(code, 2);
}

// ---- Restarts ----------------------------------------------------------------------------

using test::TempDir;

TEST(ServerRestart, FinishedImagesAreServedAfterARestart) {
  TempDir dir;
  Settings s = test_settings();
  s.results_dir = dir.path.string();
  std::string id, png, etag;
  {
    TestServer server(s);
    auto c = server.client();
    auto r = c->Post("/render?wait=1&spp=2", kScene, "text/plain");
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200);
    id = r->get_header_value("X-Job-Id");
    png = r->body;
    etag = r->get_header_value("ETag");
  }
  TestServer server(s);
  auto c = server.client();
  EXPECT_EQ(status_of(*c, id)["state"], "done");
  auto r = c->Get("/jobs/" + id + "/image");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  EXPECT_EQ(r->body, png);
  EXPECT_EQ(r->get_header_value("ETag"), etag);
  // And the restarted cache still knows it.
  auto again = c->Post("/render?wait=1&spp=2", kScene, "text/plain");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->get_header_value("X-Cache"), "hit");
}

// A short --result-ttl is kept to within a quarter of itself: the sweep runs that often.
TEST(ServerRestart, AShortResultTtlIsKeptWithoutWaitingForTheTenSecondSweep) {
  TempDir dir;
  Settings s = test_settings();
  s.results_dir = dir.path.string();
  s.result_ttl = 0.5;
  TestServer server(s);
  auto c = server.client();
  auto done = c->Post("/render?wait=1", kScene, "text/plain");
  ASSERT_TRUE(done);
  ASSERT_EQ(done->status, 200);
  const std::string id = done->get_header_value("X-Job-Id");
  const auto start = Clock::now();
  int status = 200;
  while (status != 404 && Clock::now() - start < 5s) {
    std::this_thread::sleep_for(50ms);
    status = c->Get("/jobs/" + id)->status;
  }
  EXPECT_EQ(status, 404);
  // Nowhere near the ten seconds of the sweep of a long TTL (0.5 s, then at most 0.125 s).
  EXPECT_LT(Clock::now() - start, 3s);
}

// Expiry removes finished jobs past the TTL, and an image only when no kept job names it:
// a newer cache hit on the same image keeps it readable.
TEST(ServerRestart, ExpiryKeepsImagesThatKeptJobsStillName) {
  TempDir dir;
  Settings s = test_settings();
  s.results_dir = dir.path.string();
  s.result_ttl = 0.3;
  s.expiry_every = 3600;  // expired here by hand, at the moments the test needs
  TestServer server(s);
  auto c = server.client();
  auto first = c->Post("/render?wait=1&spp=2", kScene, "text/plain");
  ASSERT_TRUE(first);
  ASSERT_EQ(first->status, 200);
  const std::string old_id = first->get_header_value("X-Job-Id");
  std::this_thread::sleep_for(500ms);
  auto second = c->Post("/render?wait=1&spp=2", kScene, "text/plain");
  ASSERT_TRUE(second);
  ASSERT_EQ(second->get_header_value("X-Cache"), "hit");
  const std::string new_id = second->get_header_value("X-Job-Id");

  server.service().expire();
  auto gone = c->Get("/jobs/" + old_id);
  ASSERT_TRUE(gone);
  EXPECT_EQ(gone->status, 404);
  auto kept = c->Get("/jobs/" + new_id + "/image");
  ASSERT_TRUE(kept);
  EXPECT_EQ(kept->status, 200);
  EXPECT_EQ(kept->body, first->body);

  // Once the last job naming it expires, the image goes too: the same request renders again.
  std::this_thread::sleep_for(500ms);
  server.service().expire();
  auto expired = c->Get("/jobs/" + new_id + "/image");
  ASSERT_TRUE(expired);
  EXPECT_EQ(expired->status, 404);
  auto third = c->Post("/render?wait=1&spp=2", kScene, "text/plain");
  ASSERT_TRUE(third);
  EXPECT_EQ(third->get_header_value("X-Cache"), "miss");
  EXPECT_EQ(third->body, first->body);
}

TEST(ServerRestart, InterruptedJobRunsAgainAfterARestart) {
  TempDir dir;
  Settings s = test_settings();
  s.results_dir = dir.path.string();
  s.shutdown_grace = 0;
  const std::string q = "width=200&height=150&spp=512&seed=5";
  std::string id, queued;
  {
    TestServer server(s);
    auto c = server.client("alice");
    id = submit(*c, q);
    ASSERT_EQ(wait_running(*c, id)["state"], "running");
    wait_for(*c, id, [](const Json& st) { return st["progress"].get<double>() > 0; });
    server.stop();  // grace 0: the render is interrupted
  }
  {
    // Kept queued, to run from the start: nothing of the render that was cut short shows.
    std::ifstream in(dir.path / "jobs" / (id + ".json"));
    const Json kept = Json::parse(in, nullptr, false);
    ASSERT_FALSE(kept.is_discarded());
    EXPECT_EQ(kept["state"], "queued") << kept.dump();
    EXPECT_EQ(kept["started_ms"], 0) << kept.dump();
    EXPECT_EQ(kept["stats"].value("spp_done", 0) + kept["stats"].value("tiles_done", 0), 0)
        << kept.dump();
  }
  TestServer server(s);
  auto c = server.client("alice");
  Json st = wait_final(*c, id, 120s);
  EXPECT_EQ(st["state"], "done") << st.dump();
  EXPECT_EQ(st["options"]["spp"], 512);
  auto r = c->Get("/jobs/" + id + "/image");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  EXPECT_EQ(r->body, local_render(kScene, {{"width", "200"}, {"height", "150"}, {"spp", "512"},
                                           {"seed", "5"}}));
  // Still the same client's job.
  auto list = json_of(c->Get("/jobs"));
  ASSERT_EQ(list["jobs"].size(), 1u);
  EXPECT_EQ(list["jobs"][0]["id"], id);
}

// ---- POST /compare -----------------------------------------------------------------------

Image gradient(int w, int h) {
  Image image(w, h);
  for (size_t i = 0; i < image.rgb.size(); ++i) image.rgb[i] = static_cast<std::uint8_t>(i * 7);
  return image;
}

TEST(ServerCompare, TwoImagesGiveMetrics) {
  TestServer server;
  auto c = server.client();
  Image a = gradient(20, 10), b = a;
  b.rgb[0] = static_cast<std::uint8_t>(b.rgb[0] + 9);
  b.rgb[30] = static_cast<std::uint8_t>(b.rgb[30] + 2);
  auto ppm_b = encode_ppm(b);
  httplib::MultipartFormDataItems items = {
      {"a", png_bytes(a), "a.png", "image/png"},
      {"b", std::string(ppm_b.begin(), ppm_b.end()), "b.ppm", "image/x-portable-pixmap"}};
  auto r = c->Post("/compare", items);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  Json j = json_of(r);
  for (const char* key : {"rmse", "psnr", "max_abs", "mean_abs", "differing_pixels"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["max_abs"], 9);
  EXPECT_EQ(j["differing_pixels"], 2);
  EXPECT_GT(j["rmse"].get<double>(), 0);
  EXPECT_EQ(j["identical"], false);
}

TEST(ServerCompare, ThresholdAndNeighborhoodAreTheGradersRules) {
  TestServer server;
  auto c = server.client();
  Image a(12, 8), b(12, 8);
  a.row(3)[4 * 3] = 200;  // one bright pixel, one column apart in the two images
  b.row(3)[5 * 3] = 200;
  a.row(6)[1 * 3 + 1] = 4;  // a small difference
  httplib::MultipartFormDataItems items = {{"a", png_bytes(a), "a.png", "image/png"},
                                           {"b", png_bytes(b), "b.png", "image/png"}};
  for (auto [t, n] : {std::pair{0, false}, {10, false}, {0, true}, {10, true}}) {
    std::string q = "/compare?threshold=" + std::to_string(t) + (n ? "&neighborhood=1" : "");
    auto r = c->Post(q, items);
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << r->body;
    CompareOptions options;
    options.threshold = t;
    options.neighborhood = n;
    std::string error;
    auto expected = compare_images(a, b, options, &error);
    ASSERT_TRUE(expected);
    Json j = json_of(r);
    EXPECT_EQ(j["differing_pixels"], expected->differing_pixels) << q;
    EXPECT_EQ(j["threshold"], t);
    EXPECT_EQ(j["neighborhood"], n);
  }
  auto strict = json_of(c->Post("/compare?threshold=0", items));
  auto lenient = json_of(c->Post("/compare?threshold=10&neighborhood=1", items));
  EXPECT_LT(lenient["differing_pixels"].get<int>(), strict["differing_pixels"].get<int>());
  auto bad = c->Post("/compare?threshold=abc", items);
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  // max_bad_fraction reads numbers as `rayfarm compare` does: a subnormal is one, hexadecimal
  // is not.
  auto tiny = c->Post("/compare?max_bad_fraction=2e-308", items);
  ASSERT_TRUE(tiny);
  EXPECT_EQ(tiny->status, 200) << tiny->body;
  EXPECT_EQ(json_of(tiny)["match"], false);
  auto hex = c->Post("/compare?max_bad_fraction=0x1p-2", items);
  ASSERT_TRUE(hex);
  EXPECT_EQ(hex->status, 400);
}

TEST(ServerCompare, SceneAndImageRendersTheReference) {
  TestServer server;
  auto c = server.client();
  std::string mine = local_render(kScene, {{"spp", "2"}});
  httplib::MultipartFormDataItems items = {{"scene", kScene, "scene.txt", "text/plain"},
                                           {"image", mine, "mine.png", "image/png"}};
  auto r = c->Post("/compare?spp=2", items);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  Json j = json_of(r);
  EXPECT_EQ(j["identical"], true);
  EXPECT_EQ(j["rmse"], 0.0);
  EXPECT_EQ(j["differing_pixels"], 0);
  EXPECT_EQ(j["reference_job"].get<std::string>().size(), 32u);

  auto off = c->Post("/compare?spp=1", items);  // another reference: not identical
  ASSERT_TRUE(off);
  ASSERT_EQ(off->status, 200);
  EXPECT_EQ(json_of(off)["identical"], false);
}

// The reference render is waited for on the HTTP thread: it needs a waiting slot like
// ?wait=1, or many /compare requests could hold every HTTP thread.
TEST(ServerCompare, ASceneToRenderNeedsAWaitingSlot) {
  Settings s = test_settings();
  s.max_waiting_requests = 0;
  TestServer server(s);
  auto c = server.client();
  std::string mine = local_render(kScene, {{"spp", "1"}});
  auto r = c->Post("/compare", httplib::MultipartFormDataItems{
                                   {"scene", kScene, "scene.txt", "text/plain"},
                                   {"image", mine, "mine.png", "image/png"}});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 503) << r->body;
  EXPECT_EQ(error_of(r)["code"], "busy");
  EXPECT_EQ(r->get_header_value("Retry-After"), "2");
  // Nothing was rendered for it.
  EXPECT_TRUE(json_of(c->Get("/jobs"))["jobs"].empty());
  // Two images need no render and no slot.
  auto two = c->Post("/compare", httplib::MultipartFormDataItems{
                                     {"a", mine, "a.png", "image/png"},
                                     {"b", mine, "b.png", "image/png"}});
  ASSERT_TRUE(two);
  EXPECT_EQ(two->status, 200) << two->body;
}

// A client that gave up on ?wait=1 frees its waiting slot: with one slot, a second client can
// wait for its render once the first has hung up, though the first's job still runs.
TEST(ServerCompare, AWaiterThatHungUpFreesItsSlot) {
  Settings s = test_settings();
  s.max_waiting_requests = 1;
  TestServer server(s);
  auto c = server.client();
  std::string id;
  {
    RawConnection gone(server.port());
    const std::string body = kScene;
    ASSERT_TRUE(gone.send(std::string("POST /render?wait=1&") + kLong +
                          " HTTP/1.1\r\nHost: x\r\nContent-Type: text/plain\r\n"
                          "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body));
    // Its job exists and it holds the slot (taken once the job is submitted).
    const auto deadline = Clock::now() + 10s;
    bool waiting = false;
    while (Clock::now() < deadline && !(waiting && !id.empty())) {
      auto jobs = json_of(c->Get("/jobs"))["jobs"];
      if (!jobs.empty()) id = jobs[0]["id"];
      auto m = c->Get("/metrics");
      waiting = m && m->body.find("\nrayfarm_waiting_requests 1\n") != std::string::npos;
      std::this_thread::sleep_for(10ms);
    }
    ASSERT_FALSE(id.empty());
    ASSERT_TRUE(waiting);
    auto busy = c->Post("/render?wait=1&spp=1", kScene, "text/plain");
    ASSERT_TRUE(busy);
    EXPECT_EQ(busy->get_header_value("X-Wait"), "unavailable");
  }  // hangs up
  std::string mine = local_render(kScene, {{"spp", "1"}});
  std::shared_ptr<httplib::Response> r;
  const auto deadline = Clock::now() + 10s;
  do {
    auto attempt = c->Post("/compare", httplib::MultipartFormDataItems{
                                           {"scene", kScene, "scene.txt", "text/plain"},
                                           {"image", mine, "mine.png", "image/png"}});
    ASSERT_TRUE(attempt);
    r = std::make_shared<httplib::Response>(*attempt);
    if (r->status != 503) break;
    std::this_thread::sleep_for(100ms);
  } while (Clock::now() < deadline);
  EXPECT_EQ(r->status, 200) << r->body;
  // The job itself goes on (queued behind the reference, or rendering: a slow host decides).
  const std::string state = json_of(c->Get("/jobs/" + id))["state"];
  EXPECT_TRUE(state == "queued" || state == "running") << state;
  c->Delete("/jobs/" + id);
}

TEST(ServerCompare, DifferentSizesAre422) {
  TestServer server;
  auto c = server.client();
  httplib::MultipartFormDataItems items = {{"a", png_bytes(gradient(10, 10)), "a.png", "image/png"},
                                           {"b", png_bytes(gradient(10, 11)), "b.png", "image/png"}};
  auto r = c->Post("/compare", items);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 422);
  EXPECT_EQ(error_of(r)["message"], "image sizes differ: a is 10x10, b is 10x11");

  // Against a scene, the message says which size is the render's and how to match the image.
  httplib::MultipartFormDataItems scene = {{"scene", kScene, "scene.txt", "text/plain"},
                                           {"image", png_bytes(gradient(10, 11)), "s.png", "image/png"}};
  auto sized = c->Post("/compare", scene);
  ASSERT_TRUE(sized);
  EXPECT_EQ(sized->status, 422);
  const std::string message = error_of(sized)["message"];
  EXPECT_NE(message.find("the image is 10x11"), std::string::npos) << message;
  EXPECT_NE(message.find("width=10&height=11"), std::string::npos) << message;
  httplib::MultipartFormDataItems junk = {{"a", "not an image", "a.png", "image/png"},
                                          {"b", png_bytes(gradient(10, 10)), "b.png", "image/png"}};
  auto bad = c->Post("/compare", junk);
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  auto none = c->Post("/compare", httplib::MultipartFormDataItems{{"x", "y", "", ""}});
  ASSERT_TRUE(none);
  EXPECT_EQ(none->status, 400);
}

TEST(ServerCompare, OptionsComeFromFormFieldsAndUnknownOnesAreRefused) {
  TestServer server;
  auto c = server.client();
  Image a = gradient(12, 8), b = a;
  b.rgb[0] = static_cast<std::uint8_t>(b.rgb[0] + 3);
  httplib::MultipartFormDataItems items = {{"a", png_bytes(a), "a.png", "image/png"},
                                           {"b", png_bytes(b), "b.png", "image/png"},
                                           {"threshold", "3", "", ""}};
  Json j = json_of(c->Post("/compare", items));
  EXPECT_EQ(j["threshold"], 3);
  EXPECT_EQ(j["differing_pixels"], 0);
  EXPECT_EQ(j["match"], true);
  // A misspelt option is an error, not a silently exact comparison.
  auto typo = c->Post("/compare?treshold=3", items);
  ASSERT_TRUE(typo);
  EXPECT_EQ(typo->status, 400);
  EXPECT_EQ(error_of(typo)["code"], "invalid_option");
  // So is a misspelt form field (it was a 400 of another code).
  httplib::MultipartFormDataItems typo_field = items;
  typo_field.push_back({"treshold", "3", "", ""});
  auto typo_part = c->Post("/compare", typo_field);
  ASSERT_TRUE(typo_part);
  EXPECT_EQ(typo_part->status, 400);
  EXPECT_EQ(error_of(typo_part)["code"], "invalid_option") << typo_part->body;
  // Render options need a scene.
  auto render_option = c->Post("/compare?spp=4", items);
  ASSERT_TRUE(render_option);
  EXPECT_EQ(render_option->status, 400);
  // Identical images: PSNR null (JSON has no infinity).
  httplib::MultipartFormDataItems same = {{"a", png_bytes(a), "a.png", "image/png"},
                                          {"b", png_bytes(a), "b.png", "image/png"}};
  Json ident = json_of(c->Post("/compare", same));
  EXPECT_TRUE(ident["psnr"].is_null());
  EXPECT_EQ(ident["identical"], true);
  // Nothing is taken silently: a switch that is neither on nor off, an option or a part given
  // twice, an image larger than the server renders.
  for (const char* query : {"?diff=banana", "?neighborhood=2", "?threshold=1&threshold=2"}) {
    auto r = c->Post(std::string("/compare") + query, same);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << query;
    EXPECT_EQ(error_of(r)["code"], "invalid_option") << query;
    EXPECT_FALSE(error_of(r)["path"].get<std::string>().empty()) << query;
  }
  EXPECT_EQ(c->Post("/compare?diff=0&neighborhood=no", same)->status, 200);
  // Numbers as the render options read them: no spaces around, in a field or in the query.
  for (const char* value : {" 5", "5 ", "\t5", "+-5", "0x5", "5.0"}) {
    httplib::MultipartFormDataItems spaced = same;
    spaced.push_back({"threshold", value, "", ""});
    auto r = c->Post("/compare", spaced);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << "[" << value << "]";
    EXPECT_EQ(error_of(r)["path"], "threshold") << "[" << value << "]";
  }
  EXPECT_EQ(c->Post("/compare?threshold=%205", same)->status, 400);
  EXPECT_EQ(json_of(c->Post("/compare?threshold=%2B5", same))["threshold"], 5);
  httplib::MultipartFormDataItems twice = same;
  twice.push_back({"a", png_bytes(b), "a2.png", "image/png"});
  auto dup = c->Post("/compare", twice);
  EXPECT_EQ(dup->status, 400);
  EXPECT_EQ(error_of(dup)["code"], "duplicate_part");
  Settings small = test_settings();
  small.max_pixels = 50;
  TestServer tight(small);
  auto too_big = tight.client()->Post("/compare", same);  // 12x8 = 96 pixels
  ASSERT_TRUE(too_big);
  EXPECT_EQ(too_big->status, 400);
  EXPECT_EQ(error_of(too_big)["code"], "invalid_image");
  EXPECT_NE(error_of(too_big)["message"].get<std::string>().find("over the limit of 50 pixels"),
            std::string::npos);
}

// ---- Methods, the index, and requests without a body ----------------------------------

TEST(ServerRoutes, AKnownPathWithAnotherMethodIs405WithAllow) {
  TestServer server;
  auto c = server.client();
  auto get_render = c->Get("/render");
  ASSERT_TRUE(get_render);
  EXPECT_EQ(get_render->status, 405);
  EXPECT_EQ(get_render->get_header_value("Allow"), "POST");
  EXPECT_EQ(error_of(get_render)["code"], "method_not_allowed");
  auto put_job = c->Put("/jobs/0123456789abcdef0123456789abcdef", "", "text/plain");
  ASSERT_TRUE(put_job);
  EXPECT_EQ(put_job->status, 405);
  EXPECT_EQ(put_job->get_header_value("Allow"), "GET, HEAD, DELETE");  // HEAD is GET's
  auto nothing = c->Get("/nothing");
  ASSERT_TRUE(nothing);
  EXPECT_EQ(nothing->status, 404);
  // The root lists the routes.
  Json index = json_of(c->Get("/"));
  bool render = false;
  for (const Json& r : index["routes"]) render |= r["method"] == "POST" && r["path"] == "/render";
  EXPECT_TRUE(render);
}

TEST(ServerRoutes, APostWithoutContentLengthHasAnEmptyBody) {
  TestServer server;
  RawConnection conn(server.port());
  // What `curl -X POST URL` sends: no Content-Length, no body.
  const auto start = Clock::now();
  ASSERT_TRUE(conn.send("POST /render?sample=minimal&wait=1 HTTP/1.1\r\nHost: x\r\n\r\n"));
  auto res = conn.read_response(5s);
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_LT(Clock::now() - start, 3s);
  EXPECT_EQ(res->header("content-type"), "image/png");
}

TEST(ServerRoutes, CurlDashDAndImagesAreNamed) {
  TestServer server;
  auto c = server.client();
  // curl -d @scene.txt: form-encoded, newlines gone.
  std::string one_line;
  for (char ch : std::string(kScene))
    if (ch != '\n' && ch != '\r') one_line += ch;
  auto r = c->Post("/render?wait=1", one_line, "application/x-www-form-urlencoded");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  EXPECT_NE(error_of(r)["message"].get<std::string>().find("--data-binary"), std::string::npos)
      << r->body;
  // Not for an option's error (the scene without its comments is fine on one line), nor for a
  // JSON scene, which may well be on one line.
  std::string valid_line;
  std::istringstream lines{std::string(kScene)};
  for (std::string line; std::getline(lines, line);)
    if (line.find('#') == std::string::npos) valid_line += line + " ";
  auto option = c->Post("/render?wait=1&spp=abc", valid_line, "application/x-www-form-urlencoded");
  ASSERT_TRUE(option);
  EXPECT_EQ(error_of(option)["code"], "invalid_option");
  EXPECT_EQ(error_of(option)["message"].get<std::string>().find("--data-binary"),
            std::string::npos)
      << option->body;
  std::string json_line = Json::parse(scene_json()).dump();
  json_line.insert(json_line.size() - 1, ", \"bogus\": 1");
  auto json = c->Post("/render?wait=1", json_line, "application/x-www-form-urlencoded");
  ASSERT_TRUE(json);
  EXPECT_EQ(json->status, 400);
  EXPECT_EQ(error_of(json)["message"].get<std::string>().find("--data-binary"), std::string::npos)
      << json->body;
  auto png = c->Post("/render?wait=1", png_bytes(gradient(4, 4)), "application/octet-stream");
  ASSERT_TRUE(png);
  EXPECT_EQ(png->status, 400);
  EXPECT_EQ(error_of(png)["message"].get<std::string>().rfind("this is a PNG image, not a scene", 0), 0u);
}

// The access log is one line per request: a client's line break or terminal escape in the
// path is written escaped, never as a line of its own.
TEST(ServerRoutes, TheAccessLogCannotBeForgedFromThePath) {
  Settings s = test_settings();
  s.access_log = true;
  TestServer server(std::move(s));
  testing::internal::CaptureStderr();
  auto r = server.client()->Get(
      "/x%0a2026-12-06T09:00:00Z%20DELETE%20/jobs/0%20200%2012%201.0ms%20name:alice%1b[2J%5c");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 404);
  server.stop();  // the line is written once the answer is sent
  const std::string log = testing::internal::GetCapturedStderr();
  EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 1) << log;
  EXPECT_NE(log.find("/x\\x0a2026-12-06T09:00:00Z DELETE /jobs/0 200 12 1.0ms "
                     "name:alice\\x1b[2J\\x5c"),
            std::string::npos)
      << log;
}

TEST(ServerRoutes, RepeatedOptionsAndUnknownCamerasAreNamed) {
  TestServer server;
  auto c = server.client();
  auto twice = c->Post("/render?spp=4&spp=8", kScene, "text/plain");
  ASSERT_TRUE(twice);
  EXPECT_EQ(twice->status, 400);
  EXPECT_EQ(error_of(twice)["message"], "'spp' is given more than once");
  // The same pair twice too (the library keeps one of identical pairs), on any route.
  for (const char* target : {"/render?spp=4&spp=4", "/render?sample=cho&spp=1&sample=cho",
                             "/check?course=1&course=1", "/render?s%70p=4&spp=4"}) {
    auto same = c->Post(target, kScene, "text/plain");
    ASSERT_TRUE(same);
    EXPECT_EQ(same->status, 400) << target;
    EXPECT_EQ(error_of(same)["code"], "invalid_option") << target;
  }
  auto camera = c->Post("/render?camera=nope", kScene, "text/plain");
  ASSERT_TRUE(camera);
  EXPECT_EQ(camera->status, 400);
  EXPECT_EQ(error_of(camera)["message"], "no camera named 'nope'; the scene's cameras: cam1");
}

TEST(ServerRoutes, TheWorkLimitSaysWhatWouldFit) {
  TestServer server;
  auto r = server.client()->Post("/render?spp=1000&width=4000&height=4000", kScene, "text/plain");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 422);
  EXPECT_EQ(error_of(r)["message"],
            "the job asks for 144,000,000,000 ray paths (16000000 pixels x spp 1000 x (max_depth 8 "
            "+ 1)); the limit is 8,000,000,000: lower spp to 55 or less, or the size");
}

// ---- The roster: named users -------------------------------------------------------------

TEST(ServerRoster, NamesFromATokensFileOwnJobsAndHaveTheirOwnLimits) {
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("rayfarm-roster-" + std::to_string(::getpid()));
  std::ofstream(file) << "# lab 3\nalice aaaaaaaaaaaaaaaaaaaaaaaa\nbob bbbbbbbbbbbbbbbbbbbbbbbb  # TA\n"
                         "grader gggggggggggggggggggggggg max_jobs=3\n";
  Settings s = test_settings();
  s.tokens_file = file.string();
  s.max_jobs_per_client = 1;
  TestServer server(s);
  auto alice = server.client("aaaaaaaaaaaaaaaaaaaaaaaa");
  auto grader = server.client("gggggggggggggggggggggggg");
  auto stranger = server.client("not-a-token-of-this-class");
  // A header claiming a name is ignored: the token decides.
  httplib::Headers claim = {{"X-Rayfarm-Client", "name:bob"}};
  auto r = alice->Post(std::string("/render?") + kLong, claim, kScene, "text/plain");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string id = Json::parse(r->body)["id"];
  EXPECT_EQ(json_of(alice->Get("/jobs/" + id))["owner"], "alice");
  // Alice's limit is the server's (1); the grader's is its own (3).
  auto second = alice->Post(std::string("/render?") + kLong, kScene, "text/plain");
  ASSERT_TRUE(second);
  EXPECT_EQ(second->status, 429);
  std::vector<std::string> graders;
  for (int i = 0; i < 3; ++i) {
    auto g = grader->Post(std::string("/render?") + kLong, kScene, "text/plain");
    ASSERT_TRUE(g);
    EXPECT_EQ(g->status, 202) << i;
    if (g->status == 202) graders.push_back(Json::parse(g->body)["id"]);
  }
  EXPECT_EQ(code_of(grader->Post(std::string("/render?") + kLong, kScene, "text/plain")), 429);
  // Only the owner cancels; a token not on the roster is refused.
  EXPECT_EQ(code_of(grader->Delete("/jobs/" + id)), 403);
  EXPECT_EQ(code_of(stranger->Get("/jobs")), 401);
  EXPECT_EQ(code_of(alice->Delete("/jobs/" + id)), 200);
  for (const std::string& g : graders) grader->Delete("/jobs/" + g);

  // A roster with errors is refused as a whole, and a reread keeps the one it had.
  std::ofstream(file, std::ios::app) << "carol short\n";
  EXPECT_FALSE(server.service().reload_roster());
  EXPECT_EQ(server.service().roster().size(), 3u);
  std::ofstream(file) << "carol cccccccccccccccccccccccc\n";
  EXPECT_TRUE(server.service().reload_roster());
  EXPECT_EQ(code_of(alice->Get("/jobs")), 401);
  EXPECT_EQ(code_of(server.client("cccccccccccccccccccccccc")->Get("/jobs")), 200);
  std::filesystem::remove(file);
}

TEST(ServerRoster, ParseErrorsArePlaced) {
  std::vector<std::string> errors;
  EXPECT_FALSE(Roster::parse("ann 0123456789abcdef0123\nann 0123456789abcdef0124\nbo\n"
                             "cy 0123456789abcdef0125 max_jobs=0 colour=red\n",
                             "class.txt", &errors));
  ASSERT_EQ(errors.size(), 4u);
  EXPECT_EQ(errors[0], "class.txt:2: 'ann' is listed twice");
  EXPECT_EQ(errors[1], "class.txt:3: 'bo' has no token: write NAME TOKEN");
  EXPECT_EQ(errors[2], "class.txt:4: max_jobs must be a whole number of at least 1, got '0'");
  EXPECT_EQ(errors[3], "class.txt:4: unknown field 'colour=red' (NAME TOKEN [max_jobs=N])");
}

// A worker may take a job between the record's reading and the queue's: a queued job is
// never shown at position 0, nor a started one at any other.
TEST(JobStatus, AQueuedJobIsAtPositionOneOrLater) {
  JobRecord job;
  job.id = std::string(32, 'a');
  job.state = JobState::queued;
  EXPECT_EQ(job_status(job, 0)["queue_position"], 1);
  EXPECT_EQ(job_status(job, 3)["queue_position"], 3);
  job.state = JobState::running;
  EXPECT_EQ(job_status(job, 2)["queue_position"], 0);
}

// ---- POST /grade -------------------------------------------------------------------------

constexpr const char* kAssignment = R"({"name": "Lab", "profile": "cpsc102", "tests": [
  {"name": "spheres", "scene": "scenes/spheres.txt", "image": "spheres.png", "points": 2},
  {"name": "mirror", "scene": "scenes/mirror.txt", "image": "mirror.png", "points": 3}]})";

std::string read_source(const std::string& path) {
  std::ifstream in(std::string(RAYFARM_SOURCE_DIR "/") + path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::string lab_file(const std::string& path) {
  std::ifstream in(std::string(RAYFARM_SOURCE_DIR "/scenes/assignments/lab1/") + path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// An image large enough to take a turn at decoding (load_gate.h) beside a scene whose own load
// takes one too (it has textures): the image's turn is given back before the render, or a
// few such requests at once would each hold one turn and wait for another forever.
TEST(ServerCompare, ImagesAndTexturedScenesAtOnceDoNotWaitOnEachOther) {
  Settings s = test_settings();
  s.max_waiting_requests = 16;
  TestServer server(s);
  const std::string scene = read_source("scenes/textures.txt");
  const Image big = gradient(800, 600);  // its decode bound is several MB, past LoadGate::kSmall
  const std::string image = png_bytes(big);
  const int kClients = 2 * static_cast<int>(std::max(1u, std::thread::hardware_concurrency())) + 1;
  std::vector<std::thread> clients;
  std::atomic<int> answered{0};
  for (int i = 0; i < kClients; ++i)
    clients.emplace_back([&] {
      auto c = server.client();
      c->set_read_timeout(60, 0);
      httplib::MultipartFormDataItems items = {{"scene", scene, "scene.txt", "text/plain"},
                                               {"image", image, "mine.png", "image/png"}};
      for (const char* name : {"bricks", "checker", "slide"})
        items.push_back({std::string("textures/") + name + ".ppm",
                         read_source(std::string("scenes/textures/") + name + ".ppm"), "x.ppm",
                         ""});
      auto r = c->Post("/compare?spp=1&width=80&height=60", items);
      if (r && (r->status == 200 || r->status == 422)) ++answered;
    });
  for (std::thread& t : clients) t.join();
  EXPECT_EQ(answered.load(), kClients);
}


TEST(ServerGrade, AnUploadedAssignmentIsGradedInThePlatformsFormat) {
  TestServer server;
  auto c = server.client();
  httplib::MultipartFormDataItems items = {
      {"assignment", kAssignment, "lab.json", "application/json"},
      {"scenes/spheres.txt", lab_file("scenes/spheres.txt"), "spheres.txt", "text/plain"},
      {"scenes/mirror.txt", lab_file("scenes/mirror.txt"), "mirror.txt", "text/plain"},
      {"spheres.png", lab_file("students/ada/spheres.png"), "spheres.png", "image/png"},
      {"mirror.png", lab_file("students/ben/mirror.png"), "mirror.png", "image/png"}};
  auto r = c->Post("/grade?format=gradescope", items);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  Json j = Json::parse(r->body);
  EXPECT_EQ(j["score"], 2);
  EXPECT_EQ(j["tests"][0]["status"], "passed");
  EXPECT_EQ(j["tests"][1]["extra_data"]["hints"][0]["code"], "rounding");
  // The assignment as a field (curl -F 'assignment=<lab.json'), the format from a field.
  items[0].filename = "";
  items.push_back({"format", "junit", "", ""});
  auto x = c->Post("/grade", items);
  ASSERT_TRUE(x);
  EXPECT_EQ(x->get_header_value("Content-Type"), "application/xml");
  EXPECT_NE(x->body.find("failures=\"1\""), std::string::npos);
  items.pop_back();
  // hints: yes or no in any of the usual words; anything else is refused, not read as yes.
  for (const char* off : {"0", "false", "no"}) {
    auto without = c->Post(std::string("/grade?hints=") + off, items);
    ASSERT_TRUE(without);
    ASSERT_EQ(without->status, 200) << off;
    EXPECT_TRUE(Json::parse(without->body)["tests"][1]["hints"].empty()) << off << without->body;
  }
  auto with = c->Post("/grade?hints=yes", items);
  ASSERT_TRUE(with);
  EXPECT_FALSE(Json::parse(with->body)["tests"][1]["hints"].empty()) << with->body;
  auto odd = c->Post("/grade?hints=off", items);
  ASSERT_TRUE(odd);
  EXPECT_EQ(odd->status, 400);
  EXPECT_EQ(error_of(odd)["code"], "invalid_option");
  auto xml = c->Post("/grade?format=xml", items);
  ASSERT_TRUE(xml);
  EXPECT_EQ(xml->status, 400);
  EXPECT_EQ(error_of(xml)["path"], "format");
  // Two images under one name: which to grade is no one's guess.
  items.push_back({"spheres.png", lab_file("students/dee/spheres.png"), "spheres.png", "image/png"});
  auto twice = c->Post("/grade", items);
  ASSERT_TRUE(twice);
  EXPECT_EQ(twice->status, 400);
  EXPECT_EQ(error_of(twice)["code"], "duplicate_part");
}

// An image handed in under the other format's name is graded, with a note, as the command
// line grades a folder; a missing one names an uploaded part close to its name.
TEST(ServerGrade, AnImageUnderAnotherNameIsFoundOrNamed) {
  TestServer server;
  auto c = server.client();
  httplib::MultipartFormDataItems items = {
      {"assignment", R"({"name": "Lab", "profile": "cpsc102", "tests": [
        {"name": "spheres", "scene": "scenes/spheres.txt", "image": "spheres.ppm"},
        {"name": "mirror", "scene": "scenes/mirror.txt", "image": "mirror.png"}]})",
       "lab.json", "application/json"},
      {"scenes/spheres.txt", lab_file("scenes/spheres.txt"), "spheres.txt", "text/plain"},
      {"scenes/mirror.txt", lab_file("scenes/mirror.txt"), "mirror.txt", "text/plain"},
      {"spheres.png", lab_file("students/ada/spheres.png"), "spheres.png", "image/png"},
      {"mirorr.png", lab_file("students/ada/mirror.png"), "mirorr.png", "image/png"}};
  auto r = c->Post("/grade", items);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  const Json j = Json::parse(r->body);
  EXPECT_EQ(j["tests"][0]["status"], "passed") << r->body;
  EXPECT_EQ(j["tests"][0]["note"], "graded spheres.png: no spheres.ppm was uploaded") << r->body;
  EXPECT_EQ(j["tests"][1]["status"], "failed") << r->body;
  EXPECT_NE(j["tests"][1]["message"].get<std::string>().find(
                "your image mirror.png was not uploaded; a part named 'mirorr.png' was"),
            std::string::npos)
      << r->body;
}

TEST(ServerGrade, AStoredAssignmentIsNamedAndItsFolderIsAFence) {
  Settings s = test_settings();
  s.assignments_dir = RAYFARM_SOURCE_DIR "/scenes/assignments/lab1";
  TestServer server(s);
  auto c = server.client();
  httplib::MultipartFormDataItems images;
  for (const char* name : {"spheres", "shadows", "mirror", "glint"})
    images.push_back({std::string(name) + ".png", lab_file(std::string("students/ada/") + name + ".png"),
                      "x.png", "image/png"});
  auto r = c->Post("/grade?assignment=lab1", images);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(Json::parse(r->body)["score"], 10);
  for (const char* name : {"../lab1/lab1", "/etc/passwd", "nothing"}) {
    auto bad = c->Post(std::string("/grade?assignment=") + name, images);
    ASSERT_TRUE(bad);
    EXPECT_EQ(bad->status, 404) << name;
  }
  // An uploaded assignment beside a stored one's name: neither is taken silently.
  httplib::MultipartFormDataItems both = images;
  both.push_back({"assignment", lab_file("lab1.json"), "lab1.json", "application/json"});
  auto two = c->Post("/grade?assignment=lab1", both);
  ASSERT_TRUE(two);
  EXPECT_EQ(two->status, 400) << two->body;
  EXPECT_EQ(error_of(two)["code"], "invalid_option");

  // A stored assignment's lock (NAME.lock.json, as --freeze writes it) is checked as the
  // command line checks it: references that differ grade nothing. The lock is no assignment.
  TempDir dir;
  std::filesystem::copy(RAYFARM_SOURCE_DIR "/scenes/assignments/lab1", dir.path,
                        std::filesystem::copy_options::recursive);
  Settings locked = test_settings();
  locked.assignments_dir = dir.path.string();
  TestServer frozen(locked);
  auto f = frozen.client();
  for (const std::string& lock :
       {std::string(R"({"render_version": 5, "tests": {"Two spheres on a floor": )"
                    R"({"reference_sha256": "00", "reference_key": "x"}}})"),
        std::string("{ not json")}) {
    std::ofstream(dir.path / "lab1.lock.json") << lock;
    auto checked = f->Post("/grade?assignment=lab1", images);
    ASSERT_TRUE(checked);
    ASSERT_EQ(checked->status, 200) << checked->body;
    const Json answer = Json::parse(checked->body);
    EXPECT_EQ(answer["score"], 0) << answer.dump();
    EXPECT_TRUE(answer["tests"].empty()) << answer.dump();
    EXPECT_EQ(answer["error"].get<std::string>().rfind(
                  "the references are not the ones in lab1.lock.json: ", 0),
              0u)
        << answer.dump();
  }
  EXPECT_EQ(f->Post("/grade?assignment=lab1.lock", images)->status, 404);
}

TEST(ServerGrade, AssignmentErrorsAre400WithTheirPath) {
  TestServer server;
  auto c = server.client();
  httplib::MultipartFormDataItems items = {
      {"assignment", R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt", "points": -1}]})",
       "a.json", "application/json"}};
  auto r = c->Post("/grade", items);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  EXPECT_EQ(error_of(r)["code"], "invalid_assignment");
  EXPECT_EQ(error_of(r)["path"], "/tests/0/points");
  // A scene the upload does not carry fails its test, not the request.
  items = {{"assignment", R"({"name": "x", "tests": [{"name": "a", "scene": "../../etc/passwd"}]})",
            "a.json", "application/json"}};
  Json j = Json::parse(c->Post("/grade", items)->body);
  EXPECT_EQ(j["tests"][0]["status"], "error");
  auto unknown = c->Post("/grade?spp=2", items);
  EXPECT_EQ(unknown->status, 400);
  // A syntax error is placed by line and column members, as a scene's is.
  items = {{"assignment", "{\"name\": \"x\",\n \"tests\": [}", "a.json", "application/json"}};
  auto syntax = c->Post("/grade", items);
  ASSERT_TRUE(syntax);
  EXPECT_EQ(syntax->status, 400);
  EXPECT_EQ(error_of(syntax)["code"], "invalid_assignment");
  EXPECT_EQ(error_of(syntax)["line"], 2) << syntax->body;
  EXPECT_TRUE(error_of(syntax)["column"].is_number()) << syntax->body;
}

// A scene's texture is the part named by its path from the assignment, however the scene
// writes it ("../textures/x.ppm" from a scene in scenes/ is "textures/x.ppm").
TEST(ServerGrade, TexturesArePartsNamedByTheirPathFromTheAssignment) {
  TestServer server;
  auto c = server.client();
  std::string scene = read_source("scenes/textures.txt");
  for (std::size_t at; (at = scene.find(" textures/")) != std::string::npos;)
    scene.replace(at, 10, " ../textures/");
  httplib::MultipartFormDataItems items = {
      {"assignment", R"({"name": "x", "tests": [{"name": "t", "scene": "scenes/t.txt", "image": "t.png"}]})",
       "a.json", "application/json"},
      {"scenes/t.txt", scene, "t.txt", "text/plain"}};
  for (const char* name : {"bricks", "checker", "slide"})
    items.push_back({std::string("textures/") + name + ".ppm",
                     read_source(std::string("scenes/textures/") + name + ".ppm"), "x.ppm", ""});
  auto r = c->Post("/grade?format=json", items);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  const Json j = Json::parse(r->body);
  EXPECT_FALSE(j.contains("error") && !j["error"].is_null() && j["error"] != "") << r->body;
  EXPECT_EQ(j["tests"][0]["status"], "failed") << r->body;  // graded: the image is missing
  // A path that climbs out of the assignment is refused, whatever parts there are.
  scene = read_source("scenes/textures.txt");
  for (std::size_t at; (at = scene.find(" textures/")) != std::string::npos;)
    scene.replace(at, 10, " ../../textures/");
  items[1].content = scene;
  const Json out = Json::parse(c->Post("/grade?format=json", items)->body);
  EXPECT_NE(out["error"].get<std::string>().find("outside the assignment's folder"),
            std::string::npos) << out;
}

// A part without a name is no part of any route's: the body is refused as malformed.
TEST(ServerGrade, APartWithoutANameIsABadBody) {
  TestServer server;
  for (const char* route : {"/grade", "/compare", "/render", "/check"}) {
    auto c = server.client();
    httplib::MultipartFormDataItems items = {{"a", "x", "a.ppm", ""}, {"", "xx", "", ""}};
    auto r = c->Post(route, items);
    ASSERT_TRUE(r) << route;
    EXPECT_EQ(r->status, 400) << route;
    EXPECT_EQ(error_of(r)["code"], "bad_multipart") << route << r->body;
    EXPECT_EQ(r->get_header_value("Connection"), "close") << route;
    EXPECT_EQ(r->get_header_value_count("Connection"), 1u) << route;
    EXPECT_FALSE(r->has_header("Keep-Alive")) << route;  // it is closing: none to keep
  }
}

TEST(ServerRender, ASceneSentTwiceIsRefused) {
  TestServer server;
  auto c = server.client();
  httplib::MultipartFormDataItems items = {{"scene", kScene, "a.txt", "text/plain"},
                                           {"scene", kScene, "b.txt", "text/plain"}};
  for (const char* route : {"/render", "/check"}) {
    auto r = c->Post(route, items);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << route;
    EXPECT_EQ(error_of(r)["code"], "duplicate_part") << route;
  }
}

TEST(ServerCompare, DiffAnswersAPng) {
  TestServer server;
  auto c = server.client();
  Image a = gradient(16, 9), b = a;
  b.rgb[5] = static_cast<std::uint8_t>(b.rgb[5] + 50);
  httplib::MultipartFormDataItems items = {{"a", png_bytes(a), "a.png", "image/png"},
                                           {"b", png_bytes(b), "b.png", "image/png"}};
  auto r = c->Post("/compare?diff=1", items);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  EXPECT_EQ(r->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(decode_or_fail(r->body), diff_image(a, b, {}));
  // The figures come with the heat map, as headers: one request, not two.
  EXPECT_EQ(r->get_header_value("X-Compare-Differing-Pixels"), "1");
  EXPECT_EQ(r->get_header_value("X-Compare-Max-Abs"), "50");
  EXPECT_EQ(r->get_header_value("X-Compare-Identical"), "false");
  EXPECT_EQ(r->get_header_value("X-Compare-Match"), "false");
  auto json = c->Post("/compare", items);
  ASSERT_TRUE(json);
  EXPECT_EQ(r->get_header_value("X-Compare-Rmse"), json_of(json)["rmse"].dump());
}

// ---- Textures uploaded with the scene ----------------------------------------------------

// A texplane whose texture entity names a path up a directory, and a projector that names an
// absolute path directly: both are only keys of the upload.
constexpr const char* kTexScene = R"(camera cam
{ pixeldim 40 30
  worlddim 8 6
  viewpoint 4 3 5 }
material wall
{ ambient 1 1 1
  diffuse 3 3 3 }
light lamp
{ location 4 3 2
  emissivity 4 4 4 }
plane floor
{ material wall
  normal 0 1 0
  point 0 -1 0 }
texture brick
{ filename ../images/brick.ppm }
texplane back
{ material wall
  normal 0 0 1
  point 0 0 -4
  xdir 1 0 0
  dimensions 8 6
  texname brick
  mode 0 }
projector slide
{ emissivity 5 5 5
  location 4 3 2
  point 2 1.5 0
  normal 0 0 1
  xdir 1 0 0
  dimensions 4 3
  texname /slides/mike.ppm
  mode 0 }
)";

// One texplane naming `path` directly.
std::string one_texture_scene(const std::string& path) {
  const std::string text = kTexScene;
  std::string scene = text.substr(0, text.find("texture brick")) +
                      "texplane back\n{ material wall\n  normal 0 0 1\n  point 0 0 -4\n"
                      "  xdir 1 0 0\n  dimensions 8 6\n  texname PATH\n  mode 0 }\n";
  return scene.replace(scene.find("PATH"), 4, path);
}

// A 4x4 P3 texture as the course writes them (a comment in the header); `seed` picks texels.
std::string texture_ppm(int seed) {
  std::string s = "P3\n# a test texture\n4 4\n255\n";
  for (int i = 0; i < 16; ++i)
    for (int c = 0; c < 3; ++c)
      s += std::to_string((seed * 53 + i * 29 + c * 71) % 256) + (c == 2 ? "\n" : " ");
  return s;
}

using Files = std::map<std::string, std::string>;

Files tex_files(int brick, int slide) {
  return {{"../images/brick.ppm", texture_ppm(brick)}, {"/slides/mike.ppm", texture_ppm(slide)}};
}

// The local render's side: texture files from a map, as FileResolver reads them from disk.
class MapResolver final : public ResourceResolver {
 public:
  explicit MapResolver(Files files) : files_(std::move(files)) {}
  std::optional<std::string> read(const std::string& path, std::string& error) const override {
    auto it = files_.find(path);
    if (it != files_.end()) return it->second;
    error = "no such file";
    return std::nullopt;
  }

 private:
  Files files_;
};

std::string local_textured(const std::string& text, const Files& files,
                           const std::vector<std::pair<std::string, std::string>>& opts) {
  MapResolver resolver(files);
  return local_render(text, opts, ImageFormat::png, &resolver);
}

httplib::MultipartFormDataItems upload(const std::string& scene, const Files& textures) {
  httplib::MultipartFormDataItems items = {{"scene", scene, "scene.txt", "text/plain"}};
  for (const auto& [path, bytes] : textures)
    items.push_back({path, bytes, "texture.ppm", "image/x-portable-pixmap"});
  return items;
}

Rendered render_upload(httplib::Client& c, const std::string& q, const std::string& scene,
                       const Files& textures) {
  auto r = c.Post(query("/render", "wait=1" + (q.empty() ? "" : "&" + q)), upload(scene, textures));
  EXPECT_TRUE(r);
  if (!r) return {};
  EXPECT_EQ(r->status, 200) << r->body;
  return {r->get_header_value("X-Cache"), r->get_header_value("ETag"),
          r->get_header_value("X-Job-Id"), r->body};
}

// 1-based line and column of the first `needle` in `text`.
std::pair<int, int> place_of(const std::string& text, const std::string& needle) {
  const size_t at = text.find(needle);
  const size_t line_start = text.rfind('\n', at);
  const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + at, '\n'));
  return {line, static_cast<int>(at - (line_start == std::string::npos ? 0 : line_start + 1)) + 1};
}

bool contains(const Json& s, const std::string& part) {
  return s.is_string() && s.get<std::string>().find(part) != std::string::npos;
}

TEST(ServerTextures, UploadedTexturesRenderLikeTheLocalRender) {
  TestServer server;
  auto c = server.client();
  const Files files = tex_files(1, 2);
  const std::string expected = local_textured(kTexScene, files, {{"spp", "2"}});
  EXPECT_EQ(render_upload(*c, "spp=2", kTexScene, files).png, expected);
  // The textures show in the image: other texels, other pixels.
  EXPECT_NE(local_textured(kTexScene, tex_files(3, 2), {{"spp", "2"}}), expected);
  EXPECT_NE(local_textured(kTexScene, tex_files(1, 3), {{"spp", "2"}}), expected);

  // POST /compare renders its reference from the same parts.
  auto items = upload(kTexScene, files);
  items.push_back({"image", expected, "mine.png", "image/png"});
  auto r = c->Post("/compare?spp=2", items);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json_of(r)["identical"], true);
}

TEST(ServerTextures, MissingTextureIs400WithItsPathAndPlace) {
  TestServer server;
  auto c = server.client();
  auto r = c->Post("/render", upload(kTexScene, {{"../images/brick.ppm", texture_ppm(1)}}));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  Json e = error_of(r);
  EXPECT_EQ(e["code"], "invalid_scene");
  EXPECT_TRUE(contains(e["message"], "'/slides/mike.ppm'")) << e.dump();
  auto [line, column] = place_of(kTexScene, "/slides/mike.ppm");
  EXPECT_EQ(e["line"], line);
  EXPECT_EQ(e["column"], column);
  ASSERT_EQ(e["errors"].size(), 1u);
  EXPECT_EQ(e["errors"][0]["code"], "texture-missing");

  // A plain body carries no textures: each is missing, at its own place.
  auto plain = c->Post("/render", kTexScene, "text/plain");
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->status, 400);
  e = error_of(plain);
  ASSERT_EQ(e["errors"].size(), 2u) << e.dump();
  EXPECT_TRUE(contains(e["errors"][0]["message"], "'../images/brick.ppm'"));
  EXPECT_EQ(e["errors"][0]["line"], place_of(kTexScene, "../images/brick.ppm").first);
  EXPECT_EQ(e["errors"][0]["column"], place_of(kTexScene, "../images/brick.ppm").second);
  EXPECT_TRUE(contains(e["errors"][1]["message"], "'/slides/mike.ppm'"));

  // Bytes that are no image: a scene error at the same place.
  auto junk = c->Post("/render", upload(kTexScene, {{"../images/brick.ppm", "P3\n4 4\n"},
                                                    {"/slides/mike.ppm", texture_ppm(2)}}));
  ASSERT_TRUE(junk);
  EXPECT_EQ(junk->status, 400);
  EXPECT_EQ(error_of(junk)["errors"][0]["code"], "texture-invalid");
  EXPECT_EQ(error_of(junk)["line"], place_of(kTexScene, "../images/brick.ppm").first);
}

TEST(ServerTextures, PartTheSceneDoesNotNameIs400) {
  TestServer server;
  auto c = server.client();
  Files typo = tex_files(1, 2);
  typo["images/brick.ppm"] = texture_ppm(1);
  auto r = c->Post("/render", upload(kTexScene, typo));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  Json e = error_of(r);
  EXPECT_EQ(e["code"], "unknown_part");
  EXPECT_TRUE(contains(e["message"], "'images/brick.ppm'")) << e.dump();
  EXPECT_TRUE(contains(e["message"], "did you mean '../images/brick.ppm'")) << e.dump();

  auto none = c->Post("/render", upload(kScene, {{"brick.ppm", texture_ppm(1)}}));
  ASSERT_TRUE(none);
  EXPECT_EQ(none->status, 400);
  EXPECT_EQ(error_of(none)["code"], "unknown_part");

  // Sent twice: which one was meant?
  auto items = upload(kTexScene, tex_files(1, 2));
  items.push_back({"/slides/mike.ppm", texture_ppm(3), "again.ppm", "image/x-portable-pixmap"});
  auto twice = c->Post("/render", items);
  ASSERT_TRUE(twice);
  EXPECT_EQ(twice->status, 400);
  EXPECT_EQ(error_of(twice)["code"], "duplicate_part");

  // /compare's own parts are 'scene' and 'image'; anything else must be a texture.
  items = upload(kTexScene, typo);
  items.push_back({"image", png_bytes(gradient(40, 30)), "mine.png", "image/png"});
  auto compare = c->Post("/compare", items);
  ASSERT_TRUE(compare);
  EXPECT_EQ(compare->status, 400);
  EXPECT_EQ(error_of(compare)["code"], "unknown_part");

  // /check says so as the render would refuse it: an error of its answer, not silence.
  auto checked = c->Post("/check", upload(kTexScene, typo));
  ASSERT_TRUE(checked);
  ASSERT_EQ(checked->status, 200) << checked->body;
  const Json answer = json_of(checked);
  EXPECT_EQ(answer["ok"], false);
  bool said = false;
  for (const Json& error : answer["errors"])
    said |= error["code"] == "unknown_part" &&
            contains(error["message"], "did you mean '../images/brick.ppm'");
  EXPECT_TRUE(said) << answer.dump();
  auto named = c->Post("/check", upload(kTexScene, tex_files(1, 2)));
  ASSERT_TRUE(named);
  EXPECT_EQ(json_of(named)["ok"], true) << named->body;
}

TEST(ServerTextures, TooManyOrTooLargeTexturesAre422) {
  Settings s = test_settings();
  s.max_textures = 1;
  s.max_texture_bytes = 300;
  TestServer server(s);
  auto c = server.client();
  auto uploads = c->Post("/render", upload(kTexScene, tex_files(1, 2)));
  auto named = c->Post("/render", upload(kTexScene, {{"../images/brick.ppm", texture_ppm(1)}}));
  for (auto* r : {&uploads, &named}) {
    ASSERT_TRUE(*r);
    EXPECT_EQ((*r)->status, 422) << (*r)->body;
    EXPECT_EQ(error_of(*r)["code"], "limit_exceeded");
    EXPECT_EQ(error_of(*r)["limit"], "max_textures");
  }
  const std::string scene = one_texture_scene("big.ppm");
  const std::string big = texture_ppm(1) + std::string(300, ' ');
  auto large = c->Post("/render", upload(scene, {{"big.ppm", big}}));
  ASSERT_TRUE(large);
  EXPECT_EQ(large->status, 422);
  EXPECT_EQ(error_of(large)["limit"], "max_texture_bytes");
  EXPECT_TRUE(contains(error_of(large)["message"], "'big.ppm'"));
  auto ok = c->Post("/render", upload(scene, {{"big.ppm", texture_ppm(1)}}));
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 202) << ok->body;

  // A small file declaring more pixels than the server renders is refused by its header, at
  // the place that names it: a 200 KB PNG of 8192 x 8192 took 300 MB to decode.
  Settings few = test_settings();
  few.max_pixels = 16;
  TestServer narrow(few);
  auto wide = narrow.client()->Post("/render", upload(scene, {{"big.ppm", "P6\n5 4\n255\n" + std::string(60, 'x')}}));
  ASSERT_TRUE(wide);
  EXPECT_EQ(wide->status, 400) << wide->body;
  EXPECT_TRUE(contains(error_of(wide)["message"], "big.ppm")) << wide->body;
  auto fits = narrow.client()->Post("/render", upload(scene, {{"big.ppm", texture_ppm(1)}}));
  ASSERT_TRUE(fits);
  EXPECT_NE(fits->status, 400) << fits->body;

  // The body limit still holds for the request as a whole.
  Settings small = test_settings();
  small.max_body_bytes = 4096;
  TestServer tight(small);
  auto over = tight.client()->Post("/render", upload(scene, {{"big.ppm", std::string(5000, ' ')}}));
  ASSERT_TRUE(over);
  EXPECT_EQ(over->status, 413);
}

TEST(ServerTextures, LimitsAreFlagsAndEnvironmentVariables) {
  int code = 0;
  auto s = parse_flags({"rayfarmd"}, code);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->max_textures, 16);
  EXPECT_EQ(s->max_texture_bytes, 8u << 20);
  s = parse_flags({"rayfarmd", "--max-textures", "3", "--max-texture-bytes", "1000"}, code);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->max_textures, 3);
  EXPECT_EQ(s->max_texture_bytes, 1000u);
  ::setenv("RAYFARM_MAX_TEXTURES", "5", 1);
  ::setenv("RAYFARM_MAX_TEXTURE_BYTES", "2048", 1);
  s = parse_flags({"rayfarmd"}, code);
  ::unsetenv("RAYFARM_MAX_TEXTURES");
  ::unsetenv("RAYFARM_MAX_TEXTURE_BYTES");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->max_textures, 5);
  EXPECT_EQ(s->max_texture_bytes, 2048u);
}

TEST(ServerTextures, TextureBytesArePartOfTheCacheKey) {
  TestServer server;
  auto c = server.client();
  Rendered first = render_upload(*c, "", kTexScene, tex_files(1, 2));
  EXPECT_EQ(first.cache, "miss");
  Rendered same = render_upload(*c, "", kTexScene, tex_files(1, 2));
  EXPECT_EQ(same.cache, "hit");
  EXPECT_EQ(same.key, first.key);
  EXPECT_EQ(same.png, first.png);
  // Same scene, same paths, another brick: another result.
  Rendered other = render_upload(*c, "", kTexScene, tex_files(3, 2));
  EXPECT_EQ(other.cache, "miss");
  EXPECT_NE(other.key, first.key);
  EXPECT_NE(other.png, first.png);
  EXPECT_EQ(other.png, local_textured(kTexScene, tex_files(3, 2), {}));
  EXPECT_EQ(render_upload(*c, "", kTexScene, tex_files(3, 2)).cache, "hit");
  // The two files swapped between the paths: not the same request either.
  EXPECT_EQ(render_upload(*c, "", kTexScene, tex_files(2, 1)).cache, "miss");
}

// Every file name under `dir`, recursively.
std::set<std::string> file_names(const std::filesystem::path& dir) {
  std::set<std::string> names;
  for (auto& e : std::filesystem::recursive_directory_iterator(dir))
    if (e.is_regular_file()) names.insert(e.path().filename().string());
  return names;
}

TEST(ServerTextures, QueuedTextureJobRendersWithItsTexturesAfterARestart) {
  TempDir dir;
  Settings s = test_settings();
  s.results_dir = dir.path.string();
  s.shutdown_grace = 0;
  const Files files = tex_files(1, 2);
  const std::filesystem::path textures = dir.path / "textures";
  std::vector<std::string> fillers;
  std::string id;
  {
    TestServer server(s);
    auto c = server.client("alice");
    // Four long jobs take all of alice's running slots: her fifth stays queued.
    for (int i = 0; i < 4; ++i) {
      fillers.push_back(submit(*c, kLong + std::string("&seed=") + std::to_string(i)));
      ASSERT_EQ(wait_running(*c, fillers.back())["state"], "running");
    }
    auto r = c->Post("/render?spp=2", upload(kTexScene, files));
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 202) << r->body;
    id = json_of(r)["id"];
    EXPECT_EQ(status_of(*c, id)["state"], "queued");
    // On disk under the hashes of their bytes, never under the names the scene gives them.
    std::set<std::string> expected = {sha256_hex(files.at("../images/brick.ppm")),
                                      sha256_hex(files.at("/slides/mike.ppm"))};
    EXPECT_EQ(file_names(textures), expected);
    for (const std::string& name : file_names(dir.path))
      EXPECT_EQ(name.find("ppm"), std::string::npos) << name;
    server.stop();  // as if killed: the job never started
  }
  TestServer server(s);
  auto c = server.client("alice");
  for (const std::string& f : fillers) EXPECT_EQ(code_of(c->Delete("/jobs/" + f)), 200);
  Json st = wait_final(*c, id);
  EXPECT_EQ(st["state"], "done") << st.dump();
  auto r = c->Get("/jobs/" + id + "/image");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  EXPECT_EQ(r->body, local_textured(kTexScene, files, {{"spp", "2"}}));
  // A job that has ended needs its textures no more.
  auto deadline = Clock::now() + 5s;
  while (!file_names(textures).empty() && Clock::now() < deadline) std::this_thread::sleep_for(5ms);
  EXPECT_TRUE(file_names(textures).empty());
}

TEST(ServerTextures, PathsAreKeysNeverTheServersFiles) {
  TempDir dir;
  // A valid image on the server's disk, named absolutely and by climbing to it from here.
  const std::string ppm = texture_ppm(4);
  {
    std::ofstream out(dir.path / "real.ppm", std::ios::binary);
    out << ppm;
  }
  const std::string absolute = (dir.path / "real.ppm").string();
  std::string climbing;
  for (int i = 0; i < 24; ++i) climbing += "../";
  climbing += absolute.substr(1);
  TestServer server;
  auto c = server.client();
  for (const std::string& path : {absolute, climbing, std::string("/etc/passwd")}) {
    const std::string scene = one_texture_scene(path);
    auto r = c->Post("/render", upload(scene, {}));
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << path;
    Json e = error_of(r);
    EXPECT_EQ(e["errors"][0]["code"], "texture-missing") << path << ": " << e.dump();
    EXPECT_TRUE(contains(e["message"], "'" + path + "'")) << e.dump();
    EXPECT_EQ(e["line"], place_of(scene, path).first);
    EXPECT_EQ(e["column"], place_of(scene, path).second);
  }
  // Uploaded under such a name, the part is that texture.
  const std::string scene = one_texture_scene("/etc/passwd");
  Rendered r = render_upload(*c, "", scene, {{"/etc/passwd", ppm}});
  EXPECT_EQ(r.png, local_textured(scene, {{"/etc/passwd", ppm}}, {}));
}

// A bundled sample's textures are files of the samples directory, read at start: a request
// for it names none, and a sample whose texture lies outside the directory is not offered.
TEST(ServerTextures, BundledSampleRendersWithTheTexturesBesideIt) {
  TempDir dir;
  auto write = [](const std::filesystem::path& p, const std::string& bytes) {
    std::filesystem::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << bytes;
  };
  const std::string inside = "# a texture beside it\n" + one_texture_scene("maps/brick.ppm");
  write(dir.path / "samples" / "inside.txt", inside);
  write(dir.path / "samples" / "maps" / "brick.ppm", texture_ppm(6));
  write(dir.path / "samples" / "outside.txt", one_texture_scene("../brick.ppm"));
  write(dir.path / "brick.ppm", texture_ppm(6));
  Settings s = test_settings();
  s.samples_dir = (dir.path / "samples").string();
  TestServer server(s);
  auto c = server.client();
  Json list = json_of(c->Get("/samples"));
  ASSERT_EQ(list["samples"].size(), 1u) << list.dump();
  EXPECT_EQ(list["samples"][0]["name"], "inside");
  auto r = c->Post("/render?sample=inside&wait=1");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->body, local_textured(inside, {{"maps/brick.ppm", texture_ppm(6)}}, {}));
}

// ---- Samples, health, metrics, authentication --------------------------------------------

TEST(ServerInfo, SamplesListsTheBundledScenes) {
  TestServer server;
  auto c = server.client();
  auto r = c->Get("/samples");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  bool found = false;
  Json list = json_of(r);
  for (const Json& s : list["samples"])
    if (s["name"] == "cho") {
      found = true;
      EXPECT_EQ(s["render"], "/render?sample=cho");
      EXPECT_FALSE(s["description"].get<std::string>().empty());
    }
  EXPECT_TRUE(found) << r->body;
  // Each description is the scene's whole opening comment, and a JSON twin borrows its
  // model file's.
  for (const Json& s : list["samples"]) {
    const std::string d = s["description"];
    EXPECT_FALSE(d.empty()) << s["name"];
    EXPECT_TRUE(d.ends_with(".") || d.ends_with(")")) << s["name"] << ": " << d;
    if (s["name"] == "cho.json") {
      EXPECT_EQ(d.rfind("The JSON form of 'cho'. ", 0), 0u) << d;
    }
  }
}

TEST(ServerInfo, HealthzReportsQueueFigures) {
  TestServer server;
  auto c = server.client();
  auto r = c->Get("/healthz");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  Json j = json_of(r);
  EXPECT_EQ(j["status"], "ok");
  for (const char* key : {"queue_depth", "running", "queue_capacity", "workers"})
    EXPECT_TRUE(j[key].is_number()) << key;
  EXPECT_EQ(j["workers"], 2);
}

TEST(ServerInfo, MetricsArePrometheusText) {
  TestServer server;
  auto c = server.client();
  auto ok = c->Post("/render?wait=1", kScene, "text/plain");
  ASSERT_TRUE(ok);
  ASSERT_EQ(ok->status, 200);
  c->Get("/jobs/0123456789abcdef0123456789abcdef");
  const std::vector<std::string> needles = {
      "# TYPE rayfarm_jobs gauge", "rayfarm_jobs{state=\"done\"} 1\n",
      "# TYPE rayfarm_queue_depth gauge", "rayfarm_queue_depth 0\n",
      "# TYPE rayfarm_render_seconds histogram", "rayfarm_render_seconds_bucket{le=\"+Inf\"} 1\n",
      "rayfarm_render_seconds_count 1\n", "rayfarm_render_seconds_sum ",
      "# TYPE rayfarm_rays_total counter", "rayfarm_rays_total{kind=\"primary\"} 1200\n",
      "# TYPE rayfarm_http_requests_total counter",
      "rayfarm_http_requests_total{route=\"POST /render\",code=\"200\"} 1\n",
      "rayfarm_http_requests_total{route=\"GET /jobs/:id\",code=\"404\"} 1\n",
      "# TYPE rayfarm_cache_hits_total counter", "rayfarm_cache_hits_total 0\n"};
  // A request is counted once its answer is written: the client may be a moment ahead.
  std::string m;
  auto deadline = Clock::now() + 2s;
  for (;;) {
    auto r = c->Get("/metrics");
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200);
    EXPECT_EQ(r->get_header_value("Content-Type").rfind("text/plain", 0), 0u);
    m = r->body;
    bool all = true;
    for (auto& n : needles) all &= m.find(n) != std::string::npos;
    if (all || Clock::now() > deadline) break;
    std::this_thread::sleep_for(10ms);
  }
  for (auto& needle : needles) EXPECT_NE(m.find(needle), std::string::npos) << needle << "\n" << m;
  // Every sample line is `name{labels} value` with a known prefix.
  size_t pos = 0;
  while (pos < m.size()) {
    size_t end = m.find('\n', pos);
    std::string line = m.substr(pos, end - pos);
    pos = end + 1;
    if (line.empty() || line[0] == '#') continue;
    EXPECT_EQ(line.rfind("rayfarm_", 0), 0u) << line;
    EXPECT_NE(line.find(' '), std::string::npos) << line;
  }
}

TEST(ServerAuth, ConfiguredTokensAreRequired) {
  Settings s = test_settings();
  s.tokens = {"s3cret", "other"};
  TestServer server(s);
  auto none = server.client();
  auto wrong = server.client("guess");
  auto right = server.client("s3cret");
  for (auto* c : {none.get(), wrong.get()}) {
    auto r = c->Post("/render", kScene, "text/plain");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 401);
    EXPECT_EQ(error_of(r)["code"], "unauthorized");
    EXPECT_EQ(r->get_header_value("WWW-Authenticate"), "Bearer");
    EXPECT_EQ(code_of(c->Get("/jobs")), 401);
    EXPECT_EQ(code_of(c->Get("/samples")), 401);
  }
  std::string id = submit(*right);
  EXPECT_EQ(wait_final(*right, id)["state"], "done");
  EXPECT_EQ(code_of(none->Get("/jobs/" + id)), 401);
  EXPECT_EQ(code_of(none->Get("/healthz")), 200);
  EXPECT_EQ(code_of(server.client("other")->Get("/jobs")), 200);
  // The scheme in any case; two headers are no token at all.
  EXPECT_EQ(code_of(none->Get("/jobs", {{"Authorization", "bearer s3cret"}})), 200);
  EXPECT_EQ(code_of(none->Get("/jobs", {{"Authorization", "BEARER s3cret"}})), 200);
  // One or more spaces after it (RFC 9110 §11.4), and none is no token.
  EXPECT_EQ(code_of(none->Get("/jobs", {{"Authorization", "Bearer   s3cret"}})), 200);
  EXPECT_EQ(code_of(none->Get("/jobs", {{"Authorization", "Bearer    "}})), 401);
  EXPECT_EQ(code_of(none->Get("/jobs", {{"Authorization", "Bearer s3cret"},
                                         {"Authorization", "Bearer other"}})),
            401);
}

// ---- The web page and cross-origin access -------------------------------------------------

const httplib::Headers kBrowser = {{"Accept", "text/html,application/xhtml+xml,*/*;q=0.8"}};

// The files a page or script names: src="/web/x", href="/web/x" and `from './x.js'`.
std::set<std::string> web_references(const std::string& text) {
  std::set<std::string> names;
  static const std::regex ref(R"re((?:src|href)="/web/([^"]+)"|from '\./([^']+)')re");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), ref); it != std::sregex_iterator(); ++it)
    names.insert((*it)[1].matched ? (*it)[1].str() : (*it)[2].str());
  return names;
}

TEST(ServerWeb, BrowsersGetThePageAndOtherClientsTheRouteIndex) {
  TestServer server;
  auto c = server.client();
  auto page = c->Get("/", kBrowser);
  ASSERT_TRUE(page);
  ASSERT_EQ(page->status, 200);
  EXPECT_EQ(page->get_header_value("Content-Type"), "text/html; charset=utf-8");
  const std::string csp = page->get_header_value("Content-Security-Policy");
  EXPECT_NE(csp.find("default-src 'self'"), std::string::npos) << csp;
  EXPECT_NE(csp.find("img-src 'self' blob: data:"), std::string::npos) << csp;
  EXPECT_EQ(csp.find("unsafe-inline"), std::string::npos) << csp;
  EXPECT_EQ(page->get_header_value("Vary"), "Accept");
  EXPECT_NE(page->body.find("<label for=\"scene\">Scene</label>"), std::string::npos);
  // Nothing leaves the server's origin: no absolute URL in the page's markup.
  EXPECT_EQ(page->body.find("http://"), std::string::npos);
  EXPECT_EQ(page->body.find("https://"), std::string::npos);

  auto index = c->Get("/");
  ASSERT_TRUE(index);
  EXPECT_EQ(index->get_header_value("Content-Type"), "application/json");
  EXPECT_EQ(index->get_header_value("Vary"), "Accept");
  Json routes = json_of(index)["routes"];
  ASSERT_TRUE(routes.is_array());
  EXPECT_GE(routes.size(), 10u);
}

TEST(ServerWeb, EveryFileThePageNamesIsServedWithItsTypeAndRevalidates) {
  TestServer server;
  auto c = server.client();
  auto page = c->Get("/", kBrowser);
  ASSERT_TRUE(page);
  // Follow the page's references and each script's imports: a file left out of the build's
  // list (server/CMakeLists.txt) would break the page in the browser.
  std::set<std::string> todo = web_references(page->body), done;
  ASSERT_TRUE(todo.count("main.js") && todo.count("style.css"));
  while (!todo.empty()) {
    const std::string name = *todo.begin();
    todo.erase(todo.begin());
    if (!done.insert(name).second) continue;
    auto r = c->Get("/web/" + name);
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << name;
    const bool js = name.size() > 3 && name.compare(name.size() - 3, 3, ".js") == 0;
    EXPECT_EQ(r->get_header_value("Content-Type"),
              js ? "text/javascript; charset=utf-8" : "text/css; charset=utf-8") << name;
    EXPECT_EQ(r->get_header_value("X-Content-Type-Options"), "nosniff");
    EXPECT_EQ(r->body.find("http://"), std::string::npos) << name;
    EXPECT_EQ(r->body.find("https://"), std::string::npos) << name;
    const std::string etag = r->get_header_value("ETag");
    ASSERT_FALSE(etag.empty()) << name;
    auto again = c->Get("/web/" + name, {{"If-None-Match", etag}});
    ASSERT_TRUE(again);
    EXPECT_EQ(again->status, 304) << name;
    EXPECT_TRUE(again->body.empty());
    for (const std::string& more : web_references(r->body)) todo.insert(more);
  }
  EXPECT_GE(done.size(), 8u);
  auto missing = c->Get("/web/nope.js");
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status, 404);
  EXPECT_EQ(error_of(missing)["code"], "not_found");
  auto post = c->Post("/web/main.js", "", "text/plain");
  ASSERT_TRUE(post);
  EXPECT_EQ(post->status, 405);
  EXPECT_EQ(post->get_header_value("Allow"), "GET, HEAD");
}

TEST(ServerWeb, ThePageLoadsWithoutATokenAndTheApiStillNeedsOne) {
  Settings s = test_settings();
  s.tokens = {"s3cret"};
  TestServer server(s);
  auto none = server.client();
  EXPECT_EQ(code_of(none->Get("/", kBrowser)), 200);
  EXPECT_EQ(code_of(none->Get("/web/main.js")), 200);
  EXPECT_EQ(code_of(none->Get("/web/nope.js")), 404);
  EXPECT_EQ(code_of(none->Get("/jobs")), 401);
  EXPECT_EQ(code_of(none->Post("/render", kScene, "text/plain")), 401);
  // The open paths are exactly these: a look-alike path is not.
  EXPECT_EQ(code_of(none->Get("/web")), 401);
  EXPECT_EQ(code_of(none->Get("/webx/main.js")), 401);
  EXPECT_EQ(code_of(server.client("s3cret")->Get("/jobs")), 200);
}

TEST(ServerCors, OffByDefault) {
  TestServer server;
  auto c = server.client();
  auto r = c->Get("/healthz", {{"Origin", "https://grader.example.edu"}});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_FALSE(r->has_header("Access-Control-Allow-Origin"));
  auto pre = c->Options("/render", {{"Origin", "https://grader.example.edu"},
                                    {"Access-Control-Request-Method", "POST"}});
  ASSERT_TRUE(pre);
  EXPECT_EQ(pre->status, 405);
  EXPECT_FALSE(pre->has_header("Access-Control-Allow-Origin"));
  EXPECT_FALSE(pre->has_header("Access-Control-Allow-Methods"));
}

TEST(ServerCors, OnlyTheConfiguredOriginMayCallTheApiWithItsToken) {
  const std::string origin = "https://grader.example.edu";
  Settings s = test_settings();
  s.tokens = {"s3cret"};
  s.cors_origin = origin;
  TestServer server(s);
  auto none = server.client();
  // The preflight carries no token and is answered for the configured origin only.
  auto pre = none->Options("/render", {{"Origin", origin},
                                       {"Access-Control-Request-Method", "POST"},
                                       {"Access-Control-Request-Headers", "authorization,content-type"}});
  ASSERT_TRUE(pre);
  EXPECT_EQ(pre->status, 204);
  EXPECT_FALSE(pre->has_header("Content-Length"));  // a 204 says no length (RFC 9110 §8.6)
  EXPECT_EQ(pre->get_header_value("Access-Control-Allow-Origin"), origin);
  EXPECT_EQ(pre->get_header_value("Access-Control-Allow-Methods"), "POST");
  EXPECT_EQ(pre->get_header_value("Access-Control-Allow-Headers"),
            "Authorization, Content-Type, Idempotency-Key");
  auto job_pre = none->Options("/jobs/" + std::string(32, 'a'),
                               {{"Origin", origin}, {"Access-Control-Request-Method", "DELETE"}});
  ASSERT_TRUE(job_pre);
  EXPECT_EQ(job_pre->status, 204);
  EXPECT_EQ(job_pre->get_header_value("Access-Control-Allow-Methods"), "GET, HEAD, DELETE");
  for (const char* other : {"https://evil.example.com", "https://grader.example.edu:444",
                            "http://grader.example.edu"}) {
    auto bad = none->Options("/render", {{"Origin", other}, {"Access-Control-Request-Method", "POST"}});
    ASSERT_TRUE(bad);
    EXPECT_NE(bad->status / 100, 2) << other;
    EXPECT_FALSE(bad->has_header("Access-Control-Allow-Origin")) << other;
    auto get = server.client("s3cret")->Get("/jobs", {{"Origin", other}});
    ASSERT_TRUE(get);
    EXPECT_EQ(get->status, 200);
    EXPECT_FALSE(get->has_header("Access-Control-Allow-Origin")) << other;
    EXPECT_EQ(get->get_header_value("Vary"), "Origin");
  }
  // A preflight for a path the API does not have is refused.
  auto unknown = none->Options("/nope", {{"Origin", origin}, {"Access-Control-Request-Method", "GET"}});
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->status, 404);

  // The real requests: answers (errors too) readable by that origin's page, with the
  // headers it needs exposed.
  auto denied = none->Get("/jobs", {{"Origin", origin}});
  ASSERT_TRUE(denied);
  EXPECT_EQ(denied->status, 401);
  EXPECT_EQ(denied->get_header_value("Access-Control-Allow-Origin"), origin);
  auto c = server.client("s3cret");
  auto r = c->Post("/render", {{"Origin", origin}}, kScene, "text/plain");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202);
  EXPECT_EQ(r->get_header_value("Access-Control-Allow-Origin"), origin);
  const std::string exposed = r->get_header_value("Access-Control-Expose-Headers");
  EXPECT_NE(exposed.find("Location"), std::string::npos) << exposed;
  EXPECT_NE(exposed.find("Retry-After"), std::string::npos) << exposed;
  // A grader page reads /compare?diff=1's figures from its headers.
  for (const char* figure : {"X-Compare-Rmse", "X-Compare-Match", "X-Compare-Differing-Pixels"})
    EXPECT_NE(exposed.find(figure), std::string::npos) << exposed;
  EXPECT_FALSE(r->has_header("Access-Control-Allow-Credentials"));
  const std::string id = json_of(r)["id"];
  std::string stream;
  auto events = c->Get("/jobs/" + id + "/events", {{"Origin", origin}},
                       [&](const char* data, size_t n) {
                         stream.append(data, n);
                         return true;
                       });
  ASSERT_TRUE(events);
  EXPECT_EQ(events->get_header_value("Access-Control-Allow-Origin"), origin);
  EXPECT_NE(stream.find("event: done"), std::string::npos) << stream;
}

TEST(ServerCors, TheOriginIsAFlagAndAnEnvironmentVariableAndMustBeExact) {
  int code = 0;
  auto s = parse_flags({"rayfarmd"}, code);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->cors_origin, "");
  s = parse_flags({"rayfarmd", "--cors-origin", "https://Grader.Example.edu:8443"}, code);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->cors_origin, "https://grader.example.edu:8443");  // as browsers send it
  ::setenv("RAYFARM_CORS_ORIGIN", "http://localhost:3000", 1);
  s = parse_flags({"rayfarmd"}, code);
  ::unsetenv("RAYFARM_CORS_ORIGIN");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->cors_origin, "http://localhost:3000");
  for (const char* bad : {"*", "https://grader.example.edu/", "https://grader.example.edu/lab",
                          "grader.example.edu", "ftp://grader.example.edu"}) {
    code = 0;
    EXPECT_FALSE(parse_flags({"rayfarmd", "--cors-origin", bad}, code)) << bad;
    EXPECT_EQ(code, 2) << bad;
  }
}

// The farm's settings (docs/deployment.md#a-farm-of-several-machines): without --redis the
// process is the single one; the password never comes from the command line or the URL.
TEST(ServerFarmSettings, RedisOptionsAreParsedCheckedAndRefusedWhereUnsafe) {
  int code = 0;
  auto s = parse_flags({"rayfarmd"}, code);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->redis, "");
  EXPECT_EQ(s->redis_prefix, "rf:");
  EXPECT_EQ(s->heartbeat_ms, 1000);
  EXPECT_EQ(s->lease_ms, 10000);
  ::setenv("RAYFARM_REDIS", "unix:///tmp/r.sock", 1);
  s = parse_flags({"rayfarmd", "--node-id", "n1", "--heartbeat-ms", "100", "--lease-ms", "600"}, code);
  ::unsetenv("RAYFARM_REDIS");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->redis, "unix:///tmp/r.sock");
  EXPECT_EQ(s->node_id, "n1");
  EXPECT_EQ(s->lease_ms, 600);
  // A lease shorter than two heartbeats would reclaim units of live nodes.
  code = 0;
  EXPECT_FALSE(parse_flags({"rayfarmd", "--redis", "unix:///tmp/r.sock", "--heartbeat-ms", "400",
                      "--lease-ms", "600"},
                     code));
  EXPECT_EQ(code, 2);
  // A node's name is a plain word: not empty, no spaces, newlines or '*', not 3,000 long.
  for (const std::string& bad : {std::string(""), std::string("a b"), std::string("n\n1"),
                                std::string("n*"), std::string(129, 'n')}) {
    code = 0;
    EXPECT_FALSE(parse_flags({"rayfarmd", "--node-id", bad.c_str()}, code)) << bad;
    EXPECT_EQ(code, 2) << bad;
  }
  EXPECT_TRUE(parse_flags({"rayfarmd", "--node-id", "lab-3.cs.example.edu:8080"}, code));
  // No --redis-password: the password is not an option at all.
  code = 0;
  EXPECT_FALSE(parse_flags({"rayfarmd", "--redis-password", "secret"}, code));
  EXPECT_EQ(code, 2);
  // A password in the URL, or a URL of another scheme, stops the start with a clear message.
  for (const char* bad : {"redis://u:secret@host:6379", "http://host:6379", "unix://relative"}) {
    Settings st = test_settings();
    st.redis = bad;
    try {
      Service service(st);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("--redis"), std::string::npos) << e.what();
    }
  }
}

// ---- cpp-httplib 0.11.4 weaknesses, over a raw socket ------------------------------------

// A burst of connections (a class submitting at once) is queued by the kernel, not dropped:
// the library's own backlog of 5 would leave the rest to SYN retries a second later. The
// server is bound but accepts nothing here, so only the backlog can hold them.
TEST(ServerHardening, BurstOfConnectionsIsQueuedWhileTheServerIsBusy) {
  Service service(test_settings());
  HttpApi api(service);
  const int port = api.bind("127.0.0.1", 0);
  ASSERT_GT(port, 0);
  constexpr int kBurst = 32;
  std::vector<int> fds;
  for (int i = 0; i < kBurst; ++i) {
    int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<uint16_t>(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    fds.push_back(fd);
  }
  int established = 0;
  for (int fd : fds) {
    pollfd p{fd, POLLOUT, 0};
    int err = 0;
    socklen_t len = sizeof err;
    if (::poll(&p, 1, 2000) == 1 && ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) == 0 &&
        err == 0)
      ++established;
    ::close(fd);
  }
  EXPECT_EQ(established, kBurst);
}

TEST(ServerHardening, ChunkedBodyIsRefusedWithoutReadingIt) {
  Settings s = test_settings();
  s.max_body_bytes = 64 * 1024;
  TestServer server(s);
  RawConnection conn(server.port());
  ASSERT_TRUE(conn.send("POST /render HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: text/plain\r\n"
                        "Transfer-Encoding: chunked\r\n\r\n"));
  const std::string chunk = std::string("4000\r\n") + std::string(0x4000, '#') + "\r\n";
  ASSERT_TRUE(conn.send(chunk));
  auto r = conn.read_response();
  ASSERT_TRUE(r) << "no answer before the body was complete";
  EXPECT_TRUE(r->status == 411 || r->status == 413) << r->status;
  EXPECT_EQ(Json::parse(r->body, nullptr, false)["error"]["code"], "length_required");
  // The rest (3x the limit) is not read as further requests: the server ends the connection.
  for (int i = 0; i < 12; ++i)
    if (!conn.send(chunk, 500ms)) break;
  std::string extra;
  EXPECT_TRUE(conn.closed_by_peer(3s, &extra));
  EXPECT_EQ(extra.find("HTTP/1.1"), std::string::npos) << "the body was parsed as requests:\n"
                                                      << extra.substr(0, 300);
  EXPECT_EQ(code_of(server.client()->Get("/healthz")), 200);
}

// A request target in absolute form (what a client sends through a proxy) is routed by its
// path, as a server must (RFC 9112 §3.2.2); its query is kept.
TEST(ServerHardening, AnAbsoluteFormTargetIsRoutedByItsPath) {
  TestServer server;
  auto ask = [&](const std::string& line, const std::string& body = "") {
    RawConnection conn(server.port());
    const std::string length = body.empty() ? "" : "Content-Length: " +
                                                       std::to_string(body.size()) + "\r\n";
    EXPECT_TRUE(conn.send(line + "\r\nHost: 127.0.0.1\r\n" + length + "\r\n" + body));
    return conn.read_response();
  };
  auto health = ask("GET http://127.0.0.1:" + std::to_string(server.port()) + "/healthz HTTP/1.1");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
  auto upper = ask("GET HTTPS://other.example/healthz HTTP/1.1");
  ASSERT_TRUE(upper);
  EXPECT_EQ(upper->status, 200);
  auto index = ask("GET http://127.0.0.1 HTTP/1.1");  // no path: the root
  ASSERT_TRUE(index);
  EXPECT_EQ(index->status, 200);
  EXPECT_NE(index->body.find("\"routes\""), std::string::npos);
  auto rendered = ask("POST http://x/render?wait=1&spp=2 HTTP/1.1", kScene);
  ASSERT_TRUE(rendered);
  EXPECT_EQ(rendered->status, 200);
  EXPECT_EQ(rendered->body, local_render(kScene, {{"spp", "2"}}));
  auto typo = ask("GET http://x/healthz?sp=2 HTTP/1.1");
  ASSERT_TRUE(typo);
  EXPECT_EQ(typo->status, 400);
  // Only a scheme and authority go: a path naming a URL inside it is still that path, and an
  // encoded one is no absolute form.
  auto inside = ask("GET /web/http://x/healthz HTTP/1.1");
  ASSERT_TRUE(inside);
  EXPECT_EQ(inside->status, 404);
  auto encoded = ask("GET http%3A//x/healthz HTTP/1.1");
  ASSERT_TRUE(encoded);
  EXPECT_EQ(encoded->status, 404);
}

// Bodies the library would not read are never read as the next request: two lengths, a
// length that is not digits, a body on a GET, a header name with a space in it ("Content-
// Length : 5"). Each is a 400 and the end of the connection, with nothing else answered.
TEST(ServerHardening, NoBodyIsTakenForTheNextRequest) {
  TestServer server;
  const std::string smuggled = "GET /nonexistent-smuggled HTTP/1.1\r\nHost: x\r\n\r\n";
  const std::string len = std::to_string(smuggled.size());
  for (const auto& [head, code] : std::vector<std::pair<std::string, std::string>>{
           {"POST /check HTTP/1.1\r\nContent-Length: 0\r\nContent-Length: " + len + "\r\n",
            "bad_content_length"},
           {"POST /check HTTP/1.1\r\nContent-Length: +" + len + "\r\n", "bad_content_length"},
           // An empty value, which the library drops as if the line were not there.
           {"POST /render HTTP/1.1\r\nContent-Length:\r\n", "bad_content_length"},
           {"POST /check HTTP/1.1\r\nContent-Length: \t\r\n", "bad_content_length"},
           {"POST /check HTTP/1.1\r\nTransfer-Encoding:\r\n", "bad_header"},
           {"GET /healthz HTTP/1.1\r\nContent-Length: " + len + "\r\n", "unexpected_body"},
           {"OPTIONS /jobs HTTP/1.1\r\nContent-Length: " + len + "\r\n", "unexpected_body"},
           {"POST /check HTTP/1.1\r\nContent-Length : " + len + "\r\n", "bad_header"},
           // Obsolete line folding (RFC 9112 §5.2): refused, not read one way or another.
           {"POST /check HTTP/1.1\r\nX-A: 1\r\n  folded\r\nContent-Length: " + len + "\r\n",
            "bad_header"},
           {"GET /healthz HTTP/1.1\r\nX-A: 1\r\n\tfolded\r\n", "bad_header"}}) {
    RawConnection conn(server.port());
    ASSERT_TRUE(conn.send(head + "Host: 127.0.0.1\r\n\r\n" + smuggled));
    auto r = conn.read_response();
    ASSERT_TRUE(r) << head;
    EXPECT_EQ(r->status, 400) << head;
    EXPECT_EQ(Json::parse(r->body, nullptr, false)["error"]["code"], code) << head;
    std::string extra;
    EXPECT_TRUE(conn.closed_by_peer(3s, &extra)) << head;
    EXPECT_EQ(extra.find("HTTP/1.1"), std::string::npos) << head << extra.substr(0, 200);
  }
  // A method no route takes is 501 (HTTP's "not implemented"), a broken request line 400.
  for (const std::string method : {"BREW", "TRACE", "CONNECT"}) {
    RawConnection other(server.port());
    ASSERT_TRUE(other.send(method + " /render HTTP/1.1\r\nHost: x\r\n\r\n"));
    auto r = other.read_response();
    ASSERT_TRUE(r) << method;
    EXPECT_EQ(r->status, 501) << method;
    EXPECT_EQ(r->header("connection"), "close") << method;
    EXPECT_FALSE(r->has("keep-alive")) << method;
    EXPECT_EQ(Json::parse(r->body, nullptr, false)["error"]["code"], "not_implemented") << method;
  }
  for (const std::string line : {"BR(EW /render HTTP/1.1", "BREW /render FTP/1.0", "GARBAGE"}) {
    RawConnection broken(server.port());
    ASSERT_TRUE(broken.send(line + "\r\nHost: x\r\n\r\n"));
    auto r = broken.read_response();
    ASSERT_TRUE(r) << line;
    EXPECT_EQ(r->status, 400) << line;
  }
  // A GET with an empty body is still a GET.
  RawConnection conn(server.port());
  ASSERT_TRUE(conn.send("GET /healthz HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n"));
  auto ok = conn.read_response();
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200);
  // Nor does a method of the client's own become a metric's label.
  RawConnection odd(server.port());
  ASSERT_TRUE(odd.send("X\"}injected{a=\"1 /x HTTP/1.1\r\nHost: x\r\n\r\n"));
  odd.read_response();
  const std::string metrics = server.client()->Get("/metrics")->body;
  EXPECT_EQ(metrics.find("injected"), std::string::npos);
  EXPECT_NE(metrics.find("route=\"OTHER other\""), std::string::npos) << metrics.substr(0, 2000);
  // A method no route takes is counted under its path, as any other method is.
  EXPECT_NE(metrics.find("route=\"OTHER /render\",code=\"501\""), std::string::npos)
      << metrics.substr(0, 2000);
}

// A failed job's image is final: its error, as wait=1 gives it, not "not done, retry".
TEST(ServerJobs, AFailedJobsImageIsItsError) {
  Settings s = test_settings();
  s.job_timeout = 0.001;
  TestServer server(s);
  auto c = server.client();
  const std::string id = submit(*c, kLong);
  const Json final_status = wait_final(*c, id);
  ASSERT_EQ(final_status["state"], "failed");
  EXPECT_EQ(final_status["error"]["code"], "timeout") << final_status.dump();
  EXPECT_EQ(final_status["stats"]["stop_reason"], "job_timeout") << final_status.dump();
  auto r = c->Get("/jobs/" + id + "/image");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 422);
  EXPECT_FALSE(r->has_header("Retry-After"));
  EXPECT_EQ(Json::parse(r->body, nullptr, false)["error"]["limit"], "job_timeout") << r->body;
}

// --job-timeout weighs a job's own time on the render threads, not the wall clock: eight jobs
// (two clients, four running each) sharing one thread each take about eight times as long to
// finish as alone, and none is timed out for the others' load. The limit is 2.5 times a job's
// time alone, measured here first (the median of three), so the check holds on a slow or a
// sanitized build alike, and the clock of the slowest is well past it.
TEST(ServerJobs, AJobIsNotTimedOutForTheOthersLoad) {
  const std::string q = "width=160&height=120&spp=48&seed=";
  std::vector<double> alone;
  {
    Settings s = test_settings();
    s.workers = 1;
    TestServer server(s);
    auto c = server.client();
    for (int i = 0; i < 3; ++i) {
      const Json st = wait_final(*c, submit(*c, q + std::to_string(i)));
      ASSERT_EQ(st["state"], "done") << st.dump();
      alone.push_back(st["stats"]["render_ms"].get<double>());
    }
  }
  std::sort(alone.begin(), alone.end());
  Settings s = test_settings();
  s.workers = 1;
  s.job_timeout = 2.5 * alone[1] / 1000;
  TestServer server(s);
  std::vector<std::pair<std::unique_ptr<httplib::Client>, std::string>> jobs;
  for (int i = 0; i < 8; ++i) {
    auto c = server.client(i % 2 ? "ann" : "bo");
    const std::string id = submit(*c, q + std::to_string(10 + i));
    jobs.emplace_back(std::move(c), id);
  }
  double longest_ms = 0;
  for (auto& [c, id] : jobs) {
    const Json st = wait_final(*c, id);
    EXPECT_EQ(st["state"], "done") << st.dump();
    longest_ms = std::max(longest_ms, st.value("elapsed_ms", 0.0));
  }
  // They did share the thread: the last took longer on the clock than the limit allows one.
  EXPECT_GT(longest_ms, 1000 * s.job_timeout) << "alone " << alone[1] << " ms";
}

TEST(ServerHardening, OversizedBodyIsRefusedBeforeA100Continue) {
  Settings s = test_settings();
  s.max_body_bytes = 64 * 1024;
  TestServer server(s);
  RawConnection conn(server.port());
  ASSERT_TRUE(conn.send("POST /render HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: text/plain\r\n"
                        "Expect: 100-continue\r\nContent-Length: 10000000\r\n\r\n"));
  auto r = conn.read_response();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 413) << "the client was told to send the body";
  EXPECT_TRUE(conn.closed_by_peer(3s));

  // Within the limit, the client is asked for the body and the upload works.
  RawConnection ok(server.port());
  std::string body = kScene;
  ASSERT_TRUE(ok.send("POST /render HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: text/plain\r\n"
                      "Expect: 100-continue\r\nContent-Length: " +
                      std::to_string(body.size()) + "\r\n\r\n"));
  auto cont = ok.read_response();
  ASSERT_TRUE(cont);
  EXPECT_EQ(cont->status, 100);
  ASSERT_TRUE(ok.send(body));
  auto accepted = ok.read_response();
  ASSERT_TRUE(accepted);
  EXPECT_EQ(accepted->status, 202);
}

TEST(ServerHardening, CompressedBodyIs415) {
  TestServer server;
  RawConnection conn(server.port());
  // 1 KiB of zeros, gzip-compressed: a tiny bomb as far as the server may know.
  const unsigned char gz[] = {0x1f, 0x8b, 0x08, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x03,
                              0x63, 0x60, 0x18, 0x05, 0xa3, 0x60, 0x14, 0x0c, 0x77, 0x00,
                              0x00, 0xa1, 0x9e, 0x58, 0x08, 0x00, 0x04, 0x00, 0x00};
  std::string body(reinterpret_cast<const char*>(gz), sizeof gz);
  ASSERT_TRUE(conn.send(scene_post("Content-Type: text/plain\r\nContent-Encoding: gzip\r\n", body)));
  auto r = conn.read_response();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 415);
  EXPECT_EQ(Json::parse(r->body, nullptr, false)["error"]["code"], "unsupported_encoding");
}

TEST(ServerHardening, ManyPartRangeDoesNotMultiplyTheImage) {
  TestServer server;
  auto c = server.client();
  auto done = c->Post("/render?wait=1", kScene, "text/plain");
  ASSERT_TRUE(done);
  ASSERT_EQ(done->status, 200);
  std::string id = done->get_header_value("X-Job-Id");
  std::string ranges = "bytes=0-";
  for (int i = 0; i < 200; ++i) ranges += ",0-" + std::to_string(done->body.size() - 1);
  RawConnection conn(server.port());
  ASSERT_TRUE(conn.send("GET /jobs/" + id + "/image HTTP/1.1\r\nHost: 127.0.0.1\r\nRange: " +
                        ranges + "\r\n\r\n"));
  auto r = conn.read_response();
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->status == 416 || r->body.size() <= done->body.size())
      << r->status << " with " << r->body.size() << " bytes";
  // The refusal is the error document, whole (not cut into byte ranges of itself).
  EXPECT_EQ(r->status, 416);
  EXPECT_EQ(Json::parse(r->body)["error"]["code"], "range_not_satisfiable") << r->body;
}

TEST(ServerHardening, ASingleRangeGetsTheWholeImage) {
  // Ranges are not offered: a slice under status 200 would pass for a whole (broken) image.
  TestServer server;
  auto c = server.client();
  auto done = c->Post("/render?wait=1", kScene, "text/plain");
  ASSERT_TRUE(done);
  ASSERT_EQ(done->status, 200);
  auto r = c->Get("/jobs/" + done->get_header_value("X-Job-Id") + "/image",
                  {{"Range", "bytes=0-9"}});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(r->body, done->body);
  EXPECT_FALSE(r->has_header("Accept-Ranges"));
  // Nor are they offered on a HEAD answer (the library offered them there).
  for (const std::string& path :
       std::vector<std::string>{"/healthz", "/jobs/" + done->get_header_value("X-Job-Id") + "/image"}) {
    auto head = c->Head(path.c_str());
    ASSERT_TRUE(head);
    EXPECT_EQ(head->status, 200) << path;
    EXPECT_FALSE(head->has_header("Accept-Ranges")) << path;
  }
}

TEST(ServerHardening, HandlerExceptionTextIsNotSent) {
  TestServer server(test_settings(), [](httplib::Server& http) {
    http.Get("/throw", [](const httplib::Request&, httplib::Response&) {
      throw std::runtime_error("secret-internal-detail");
    });
  });
  RawConnection conn(server.port());
  ASSERT_TRUE(conn.send("GET /throw HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"));
  auto r = conn.read_response();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 500);
  EXPECT_FALSE(r->has("exception_what"));
  for (auto& [name, value] : r->headers)
    EXPECT_EQ(value.find("secret"), std::string::npos) << name;
  EXPECT_EQ(r->body.find("secret"), std::string::npos);
  EXPECT_EQ(Json::parse(r->body, nullptr, false)["error"]["code"], "internal_error");
  EXPECT_EQ(r->header("content-type"), "application/json");
}

TEST(ServerHardening, RemoteAddrHeaderDoesNotChangeWhoIsAsking) {
  TestServer server;
  RawConnection conn(server.port());
  ASSERT_TRUE(conn.send(scene_post("Content-Type: text/plain\r\nREMOTE_ADDR: 10.9.8.7\r\n", kScene)));
  auto r = conn.read_response();
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202);
  std::string id = Json::parse(r->body)["id"];
  // A plain client from the same socket address owns the job.
  auto c = server.client();
  auto list = json_of(c->Get("/jobs"));
  ASSERT_EQ(list["jobs"].size(), 1u);
  EXPECT_EQ(list["jobs"][0]["id"], id);
  // And forging the header again on another connection sees the same list, not another's.
  RawConnection other(server.port());
  ASSERT_TRUE(other.send("GET /jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nREMOTE_ADDR: 10.1.1.1\r\n\r\n"));
  auto mine = other.read_response();
  ASSERT_TRUE(mine);
  EXPECT_EQ(Json::parse(mine->body)["jobs"].size(), 1u);
}

TEST(ServerHardening, VeryLongPathsAnswerQuickly) {
  TestServer server;
  for (size_t length : {size_t(600), size_t(6000), size_t(10 * 1024)}) {
    RawConnection conn(server.port());
    auto start = Clock::now();
    ASSERT_TRUE(conn.send("GET /jobs/" + std::string(length, 'a') + "/image HTTP/1.1\r\nHost: x\r\n\r\n"));
    auto r = conn.read_response(2s);
    ASSERT_TRUE(r) << length;
    EXPECT_TRUE(r->status == 414 || r->status == 404) << r->status;
    EXPECT_LT(Clock::now() - start, 1s) << length;
  }
  EXPECT_EQ(code_of(server.client()->Get("/healthz")), 200);
}

TEST(ServerHardening, StalledClientsDoNotBlockHealthz) {
  TestServer server;
  std::vector<std::unique_ptr<RawConnection>> stalled;
  for (int i = 0; i < 8; ++i) {
    stalled.push_back(std::make_unique<RawConnection>(server.port()));
    ASSERT_TRUE(stalled.back()->send("GET /heal"));
  }
  std::this_thread::sleep_for(100ms);
  auto c = server.client();
  c->set_read_timeout(2);
  for (int i = 0; i < 3; ++i) {
    auto start = Clock::now();
    auto r = c->Get("/healthz");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
    EXPECT_LT(Clock::now() - start, 1s);
  }
}

TEST(ServerHardening, EndlessHeaderBlockIsCutOff) {
  TestServer server;
  RawConnection conn(server.port());
  ASSERT_TRUE(conn.send("GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\n"));
  std::string headers;
  for (int i = 0; i < 2000; ++i) headers += "X-Filler-" + std::to_string(i) + ": " + std::string(100, 'v') + "\r\n";
  // ~230 KiB of headers and no end: the server gives up well before the read timeout.
  auto start = Clock::now();
  conn.send(headers, 1s);
  std::string extra;
  EXPECT_TRUE(conn.closed_by_peer(3s, &extra));
  EXPECT_LT(Clock::now() - start, 4s);
  EXPECT_EQ(extra.find("HTTP/1.1 200"), std::string::npos);
  EXPECT_EQ(code_of(server.client()->Get("/healthz")), 200);
}

TEST(ServerHardening, TricklingHeadIsCutOffAtTheHeaderTimeout) {
  Settings s = test_settings();
  s.header_timeout = 1;
  TestServer server(s);
  RawConnection conn(server.port());
  auto start = Clock::now();
  ASSERT_TRUE(conn.send("GET /healthz HTTP/1.1\r\n"));
  bool closed = false;
  for (int i = 0; i < 50 && !closed; ++i) {
    if (!conn.send("X-Slow-" + std::to_string(i) + ": 1\r\n")) break;  // under the read timeout
    closed = conn.closed_by_peer(100ms);
  }
  EXPECT_TRUE(closed || conn.closed_by_peer(1s));
  EXPECT_LT(Clock::now() - start, 2500ms);
  // A prompt client on another connection is unaffected.
  EXPECT_EQ(code_of(server.client()->Get("/healthz")), 200);
}

// A body trickled a byte at a time (each within the read timeout) is cut off once it falls
// behind the minimum rate after the grace: 64 such clients once held every HTTP thread.
TEST(ServerHardening, TricklingBodyIsCutOffAtTheMinimumRate) {
  Settings s = test_settings();
  s.header_timeout = 1;
  TestServer server(s);
  RawConnection conn(server.port());
  auto start = Clock::now();
  ASSERT_TRUE(conn.send("POST /check HTTP/1.1\r\nHost: x\r\nContent-Type: text/plain\r\n"
                        "Content-Length: 100\r\n\r\n"));
  bool closed = false;
  for (int i = 0; i < 100 && !closed; ++i) {
    if (!conn.send("#")) break;
    closed = conn.closed_by_peer(200ms);
  }
  EXPECT_TRUE(closed || conn.closed_by_peer(1s));
  EXPECT_LT(Clock::now() - start, 3s);
  EXPECT_EQ(code_of(server.client()->Get("/healthz")), 200);
}

// A body cut off for falling behind, or stalled, ends its connection after a 408: what the
// client sends after it (here, requests) is never read as further requests.
TEST(ServerHardening, WhatFollowsABodyCutOffIsNeverARequest) {
  Settings s = test_settings();
  s.header_timeout = 1;
  s.access_log = false;
  TestServer server(s);
  const std::string inner = "DELETE /jobs/00000000000000000000000000000000 HTTP/1.1\r\nHost: x\r\n\r\n";
  for (const bool trickle : {true, false}) {
    RawConnection conn(server.port());
    ASSERT_TRUE(conn.send("POST /check HTTP/1.1\r\nHost: x\r\nContent-Type: text/plain\r\n"
                          "Content-Length: 1000000\r\n\r\ncamera\n"));
    const auto start = Clock::now();
    if (trickle) {
      // Whole requests as the body, each well within the read timeout, far under 8 KiB/s.
      while (Clock::now() - start < 2500ms && conn.send(inner)) std::this_thread::sleep_for(150ms);
    } else {
      std::this_thread::sleep_for(1500ms);  // past the grace, with 7 bytes of 1,000,000
      conn.send(inner + "GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n");
    }
    auto r = conn.read_response();
    ASSERT_TRUE(r) << trickle;
    EXPECT_EQ(r->status, 408) << trickle;
    EXPECT_EQ(Json::parse(r->body, nullptr, false)["error"]["code"], "request_timeout") << r->body;
    EXPECT_EQ(r->header("connection"), "close");
    std::string extra;
    EXPECT_TRUE(conn.closed_by_peer(3s, &extra)) << trickle;
    EXPECT_EQ(extra.find("HTTP/1.1"), std::string::npos) << trickle << extra.substr(0, 300);
  }
  const std::string metrics = server.client()->Get("/metrics")->body;
  EXPECT_EQ(metrics.find("DELETE"), std::string::npos) << "no request was read from a body";
}

// A multipart body the library cannot parse is refused part way through: its connection
// ends, so the rest of it is never a request, and the error says what a body needs.
TEST(ServerHardening, AMultipartBodyThatDoesNotParseEndsItsConnection) {
  TestServer server;
  const std::string smuggled = "GET /nonexistent-smuggled HTTP/1.1\r\nHost: x\r\n\r\n";
  const std::string body = "--other\r\nContent-Disposition: form-data; name=\"scene\"\r\n\r\n" +
                           std::string(kScene) + "\r\n--other--\r\n" + smuggled;
  RawConnection conn(server.port());
  ASSERT_TRUE(conn.send(scene_post("Content-Type: multipart/form-data; boundary=b\r\n", body)));
  auto r = conn.read_response();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  const Json error = Json::parse(r->body, nullptr, false)["error"];
  EXPECT_EQ(error["code"], "bad_multipart") << r->body;
  EXPECT_NE(error["message"].get<std::string>().find("--BOUNDARY--"), std::string::npos);
  std::string extra;
  EXPECT_TRUE(conn.closed_by_peer(3s, &extra));
  EXPECT_EQ(extra.find("HTTP/1.1"), std::string::npos) << extra.substr(0, 300);
}

// What the library refuses in a request's head is said as what it is.
TEST(ServerHardening, TheLibrarysRefusalsSayWhatWasWrong) {
  TestServer server;
  auto c = server.client();
  for (const std::string range : {"bytes=abc", "items=0-1", "bytes=9-3"}) {
    auto r = c->Get("/healthz", {{"Range", range}});
    ASSERT_TRUE(r) << range;
    EXPECT_EQ(r->status, 416) << range;
    EXPECT_NE(error_of(r)["message"].get<std::string>().find("not a byte range"),
              std::string::npos)
        << range << r->body;
  }
  auto long_line = c->Get("/healthz", {{"Cookie", std::string(9000, 'a')}});
  ASSERT_TRUE(long_line);
  EXPECT_EQ(long_line->status, 400);
  EXPECT_NE(error_of(long_line)["message"].get<std::string>().find("8 KiB"), std::string::npos)
      << long_line->body;
}

TEST(ServerHardening, CurlStyleFormUploadOver8KiBWorks) {
  TestServer server;
  // curl --data-binary @scene.txt labels the body a urlencoded form.
  std::string body = std::string(kScene) + "# a=b&c=d%20e\n";
  while (body.size() < 12 * 1024) body += "# padding padding padding padding padding padding\n";
  RawConnection conn(server.port());
  ASSERT_TRUE(conn.send(scene_post("Content-Type: application/x-www-form-urlencoded\r\n", body,
                                   "/render?spp=2")));
  auto r = conn.read_response();
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  std::string id = Json::parse(r->body)["id"];
  auto c = server.client();
  Json st = wait_final(*c, id);
  EXPECT_EQ(st["state"], "done");
  EXPECT_EQ(st["options"]["spp"], 2);
}

TEST(ServerConnections, KeepAliveAndPipelinedRequestsAreServed) {
  auto server = std::make_unique<TestServer>();
  auto c = server->client();
  c->set_keep_alive(true);
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(code_of(c->Get("/healthz")), 200);
    EXPECT_EQ(code_of(c->Post("/render", kScene, "text/plain")), 202);
  }
  RawConnection conn(server->port());
  std::string two = "GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n" +
                    scene_post("Content-Type: text/plain\r\n", kScene) +
                    "GET /samples HTTP/1.1\r\nHost: x\r\n\r\n";
  ASSERT_TRUE(conn.send(two));
  for (int expected : {200, 202, 200}) {
    auto r = conn.read_response();
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, expected);
  }
  // Idle keep-alive connections do not hold up a stop.
  auto start = Clock::now();
  server.reset();
  EXPECT_LT(Clock::now() - start, 1500ms);
}

TEST(ServerConnections, DepartedEventStreamClientFreesItsSlot) {
  Settings s = test_settings();
  s.max_event_streams = 1;
  TestServer server(s);
  auto c = server.client();
  std::string id = submit(*c, kLong);
  {
    RawConnection conn(server.port());
    ASSERT_TRUE(conn.send("GET /jobs/" + id + "/events HTTP/1.1\r\nHost: x\r\n\r\n"));
    std::string first;
    conn.closed_by_peer(300ms, &first);
    EXPECT_NE(first.find("text/event-stream"), std::string::npos);
  }  // gone without a word
  auto deadline = Clock::now() + 3s;
  int status = 0;
  while (Clock::now() < deadline) {
    c->Get(
        "/jobs/" + id + "/events",
        [&](const httplib::Response& res) {
          status = res.status;
          return false;  // only the status is wanted
        },
        [](const char*, size_t) { return false; });
    if (status != 503) break;
    std::this_thread::sleep_for(50ms);
  }
  EXPECT_EQ(status, 200) << "the slot of a departed client was not freed";
  c->Delete("/jobs/" + id);
}

TEST(ServerHardening, ShutdownRefusesNewWorkAndEndsWaits) {
  Settings s = test_settings();
  TestServer server(s);
  auto c = server.client();
  std::string id = submit(*c, kLong);
  int wait_status = 0;
  std::thread waiter([&] {
    auto r = server.client()->Post("/render?wait=1&" + std::string(kLong) + "&seed=1", kScene,
                                   "text/plain");
    wait_status = r ? r->status : -1;
  });
  std::this_thread::sleep_for(200ms);
  auto start = Clock::now();
  server.service().shutdown();
  waiter.join();
  EXPECT_LT(Clock::now() - start, 5s);
  EXPECT_EQ(wait_status, 202);  // the job is kept; the client polls for it later
  auto r = c->Post("/render", kScene, "text/plain");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 503);
  EXPECT_FALSE(r->get_header_value("Retry-After").empty());
  EXPECT_EQ(code_of(c->Get("/healthz")), 503);
}


// ---- Checking a scene without rendering it ----------------------------------------------

// A sphere behind the eye renders black: the warning is what tells the student why.
constexpr const char* kBehindEye = R"(camera c
{ pixeldim 40 30
  worlddim 8 6
  viewpoint 4 3 5 }
material m
{ ambient 1 1 1 }
light l
{ location 1 5 -2 }
sphere s
{ material m
  center 4 3 10
  radius 1 }
)";

TEST(ServerCheck, GivesErrorsAndWarningsWithTheirPlaces) {
  TestServer server;
  auto c = server.client();
  auto good = c->Post("/check", kScene, "text/plain");
  ASSERT_TRUE(good);
  ASSERT_EQ(good->status, 200) << good->body;
  Json g = json_of(good);
  EXPECT_EQ(g["ok"], true);
  EXPECT_EQ(g["format"], "model");
  EXPECT_TRUE(g["errors"].empty());
  EXPECT_EQ(g["scene"]["cameras"][0]["name"], "cam1");
  EXPECT_EQ(g["scene"]["cameras"][0]["width"], 40);
  EXPECT_FALSE(g.contains("error_count"));

  // Past 50 errors the list stops and the count says how many there were (the command line
  // says "60 errors, only the first 50 shown"; the answer said nothing).
  std::string many = "material m { ambient 1 }\ncamera { pixeldim 4 3 worlddim 8 6 viewpoint 4 3 5 }\n";
  for (int i = 0; i < 60; ++i) many += "sphere { material nothing center 4 3 -5 radius 1 }\n";
  auto crowded = c->Post("/check", many, "text/plain");
  ASSERT_TRUE(crowded);
  Json m = json_of(crowded);
  EXPECT_EQ(m["errors"].size(), 50u) << crowded->body;
  EXPECT_EQ(m["error_count"], 60) << crowded->body;

  auto behind = c->Post("/check", kBehindEye, "text/plain");
  ASSERT_TRUE(behind);
  Json b = json_of(behind);
  EXPECT_EQ(b["ok"], true);
  ASSERT_FALSE(b["warnings"].empty()) << behind->body;
  bool named = false;
  for (const Json& w : b["warnings"])
    named |= w["message"].get<std::string>().find("behind the eye") != std::string::npos &&
             w["line"] == 9;
  EXPECT_TRUE(named) << behind->body;

  // Errors: all of them, each with its place; still a successful check.
  auto bad = c->Post("/check", "sphere s { radious 1 }\nplane p { nromal 0 1 0 }\n", "text/plain");
  ASSERT_TRUE(bad);
  ASSERT_EQ(bad->status, 200);
  Json e = json_of(bad);
  EXPECT_EQ(e["ok"], false);
  ASSERT_GE(e["errors"].size(), 2u) << bad->body;
  EXPECT_EQ(e["errors"][0]["line"], 1);
  EXPECT_TRUE(e["errors"][0]["column"].is_number());
  EXPECT_FALSE(e.contains("scene"));

  // A scene that reads but whose image no render takes is not ok either.
  auto huge = c->Post("/check",
                      "material m { ambient 1 }\n"
                      "camera c { pixeldim 65535 65535 worlddim 8 6 viewpoint 4 3 5 }\n"
                      "sphere s { material m center 4 3 -5 radius 1 }\n",
                      "text/plain");
  ASSERT_TRUE(huge);
  ASSERT_EQ(huge->status, 200);
  Json h = json_of(huge);
  EXPECT_EQ(h["ok"], false) << huge->body;
  ASSERT_EQ(h["errors"].size(), 1u) << huge->body;
  EXPECT_EQ(h["errors"][0]["code"], "image-too-large");
  EXPECT_EQ(h["errors"][0]["line"], 2);
}

TEST(LoadGate, LargeTextsTakeTurnsSmallOnesNeverWait) {
  LoadGate gate(1);
  LoadGate::Pass first = gate.enter(LoadGate::kSmall + 1);
  EXPECT_TRUE(first.held());
  std::atomic<bool> second_in{false};
  std::thread second([&] {
    LoadGate::Pass p = gate.enter(LoadGate::kSmall + 1);
    second_in = p.held();
  });
  const auto deadline = Clock::now() + 5s;
  while (gate.waiting() == 0 && Clock::now() < deadline) std::this_thread::sleep_for(1ms);
  EXPECT_EQ(gate.waiting(), 1);
  EXPECT_FALSE(gate.enter(LoadGate::kSmall).held());  // small: at once, no pass taken
  std::this_thread::sleep_for(20ms);
  EXPECT_FALSE(second_in.load());
  { LoadGate::Pass done = std::move(first); }  // released
  second.join();
  EXPECT_TRUE(second_in.load());
  EXPECT_EQ(gate.waiting(), 0);
  EXPECT_TRUE(gate.enter(LoadGate::kSmall + 1).held());  // the second gave its pass back
}

// Every request that reads a large scene waits for a pass: with all passes held, /check of a
// 1.5 MB scene waits (and /metrics says so), and answers once one is free.
TEST(ServerCheck, LargeScenesAreReadInTurn) {
  TestServer server;
  std::string scene = kScene;
  for (int i = 0; scene.size() <= LoadGate::kSmall + (LoadGate::kSmall >> 1); ++i)
    scene += "sphere b" + std::to_string(i) + " { material chrome" +
             " center 1 2 -30 radius 0.5 }\n";
  std::vector<LoadGate::Pass> held;
  for (unsigned i = 0; i < std::max(1u, std::thread::hardware_concurrency()); ++i)
    held.push_back(server.service().enter_load(LoadGate::kSmall + 1));
  std::atomic<int> status{0};
  std::thread check([&] {
    auto r = server.client()->Post("/check", scene, "text/plain");
    status = r ? r->status : -1;
  });
  auto waiting = [&] {
    const std::string m = server.client()->Get("/metrics")->body;
    return m.find("\nrayfarm_waiting_scene_loads 1\n") != std::string::npos;
  };
  const auto deadline = Clock::now() + 10s;
  while (!waiting() && Clock::now() < deadline) std::this_thread::sleep_for(5ms);
  EXPECT_TRUE(waiting());
  EXPECT_EQ(status.load(), 0);
  held.clear();
  check.join();
  EXPECT_EQ(status.load(), 200);
  // A small scene never waited: the same check with every pass held answers.
  for (unsigned i = 0; i < std::max(1u, std::thread::hardware_concurrency()); ++i)
    held.push_back(server.service().enter_load(LoadGate::kSmall + 1));
  auto small = server.client()->Post("/check", kScene, "text/plain");
  ASSERT_TRUE(small);
  EXPECT_EQ(small->status, 200);
}

TEST(ServerCheck, CourseWarningsOnRequestAndUnknownOptionsRefused) {
  TestServer server;
  auto c = server.client();
  const std::string commented = std::string("# a comment the course's program cannot read\n") + kScene;
  auto plain = c->Post("/check", commented, "text/plain");
  auto course = c->Post("/check?course=1", commented, "text/plain");
  ASSERT_TRUE(plain && course);
  auto has_course_warning = [](const Json& j) {
    for (const Json& w : j["warnings"])
      if (w["code"].get<std::string>().rfind("course-", 0) == 0) return true;
    return false;
  };
  EXPECT_FALSE(has_course_warning(json_of(plain))) << plain->body;
  EXPECT_TRUE(has_course_warning(json_of(course))) << course->body;

  auto typo = c->Post("/check?cource=1", kScene, "text/plain");
  ASSERT_TRUE(typo);
  EXPECT_EQ(typo->status, 400);
  auto empty = c->Post("/check", "", "text/plain");
  ASSERT_TRUE(empty);
  EXPECT_EQ(empty->status, 400);
  EXPECT_EQ(error_of(empty)["code"], "empty_scene");
}

TEST(ServerRender, TheJobCarriesTheScenesWarnings) {
  TestServer server;
  auto c = server.client();
  auto r = c->Post("/render", kBehindEye, "text/plain");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  Json status = wait_final(*c, json_of(r)["id"]);
  ASSERT_FALSE(status["warnings"].empty()) << status.dump();
  EXPECT_NE(status["warnings"][0]["message"].get<std::string>().find("behind the eye"),
            std::string::npos);
  auto clean = c->Post("/render", kScene, "text/plain");
  ASSERT_TRUE(clean);
  EXPECT_TRUE(wait_final(*c, json_of(clean)["id"])["warnings"].empty());
}

TEST(ServerQuery, EveryRouteRefusesOptionsItDoesNotTake) {
  TestServer server;
  auto c = server.client();
  auto r = c->Post("/render?wait=1", kScene, "text/plain");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  const std::string id = r->get_header_value("X-Job-Id");
  ASSERT_FALSE(id.empty());
  struct Case {
    std::string path, needle;
  };
  const Case cases[] = {
      {"/jobs/" + id + "/image?format=jpg", "'format' is 'jpg'; it takes png, ppm"},
      {"/jobs/" + id + "/image?frmat=ppm", "(did you mean 'format'?)"},
      {"/jobs/" + id + "/image?format=ppm&format=png", "given more than once"},
      {"/jobs/" + id + "?verbose=1", "GET /jobs/ID; it takes no options"},
      {"/jobs?limit=5", "unknown option 'limit'"},
      {"/samples?all=1", "unknown option 'all'"},
      {"/healthz?x=1", "unknown option 'x'"},
      {"/jobs/" + id + "/events?foo=bar", "GET /jobs/ID/events; it takes no options"},
      // cpp-httplib read these as format=ppm and format=png: values never sent.
      {"/jobs/" + id + "/image?format=png=ppm", "holds a second '='"},
      {"/jobs/" + id + "/image?partial=1;format=ppm", "holds a second '='"},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(k.path);
    auto bad = c->Get(k.path);
    ASSERT_TRUE(bad);
    EXPECT_EQ(bad->status, 400);
    EXPECT_EQ(error_of(bad)["code"], "invalid_option");
    EXPECT_NE(error_of(bad)["message"].get<std::string>().find(k.needle), std::string::npos)
        << bad->body;
  }
  // A yes/no option with another value is refused where it used to mean no: wait=2 did not
  // wait. And the path names the option.
  auto wait2 = c->Post("/render?wait=2", kScene, "text/plain");
  ASSERT_TRUE(wait2);
  EXPECT_EQ(wait2->status, 400);
  EXPECT_EQ(error_of(wait2)["path"], "wait");
  auto twice = c->Post("/render?spp=2=3", kScene, "text/plain");
  ASSERT_TRUE(twice);
  EXPECT_EQ(twice->status, 400);
  EXPECT_EQ(error_of(twice)["path"], "spp");
  // What the routes do take still works.
  auto ppm = c->Get("/jobs/" + id + "/image?format=ppm");
  ASSERT_TRUE(ppm);
  EXPECT_EQ(ppm->status, 200);
  EXPECT_EQ(ppm->body.rfind("P6", 0), 0u);
  auto partial = c->Get("/jobs/" + id + "/image?partial=1");
  ASSERT_TRUE(partial);
  EXPECT_EQ(partial->status, 200);
}

TEST(ServerCache, ASceneAndItsTwinShareOneResultWhateverCarriesTheOptions) {
  // The key is the scene and the options in effect: a JSON scene whose render block asks for
  // spp 2 and its model twin sent with ?spp=2 are one render.
  auto read = [](const char* name) {
    std::ifstream in(std::string(RAYFARM_SOURCE_DIR "/scenes/") + name, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  std::string json = read("minimal.json");
  ASSERT_FALSE(json.empty());
  json = json.substr(0, json.rfind('}')) + ", \"render\": {\"spp\": 2}}";
  TestServer server;
  auto c = server.client();
  auto first = c->Post("/render?wait=1&width=40&height=30", json, "application/json");
  ASSERT_TRUE(first);
  ASSERT_EQ(first->status, 200) << first->body;
  EXPECT_EQ(first->get_header_value("X-Cache"), "miss");
  auto twin = c->Post("/render?wait=1&width=40&height=30&spp=2", read("minimal.txt"), "text/plain");
  ASSERT_TRUE(twin);
  ASSERT_EQ(twin->status, 200) << twin->body;
  EXPECT_EQ(twin->get_header_value("X-Cache"), "hit");
  EXPECT_EQ(twin->body, first->body);
  auto other = c->Post("/render?wait=1&width=40&height=30&spp=3", read("minimal.txt"), "text/plain");
  ASSERT_TRUE(other);
  EXPECT_EQ(other->get_header_value("X-Cache"), "miss");
}

// ---- Priorities and Idempotency-Key ---------------------------------------------------------

TEST(ServerPriority, TheStatusShowsItAndWaitMeansInteractive) {
  TestServer server;
  auto c = server.client();
  const std::string batch = submit(*c, "priority=batch&spp=2");
  Json st = status_of(*c, batch);
  EXPECT_EQ(st["priority"], "batch");
  EXPECT_EQ(st["options"]["priority"], "batch");
  EXPECT_EQ(status_of(*c, submit(*c, "spp=3"))["priority"], "normal");
  auto waited = c->Post("/render?wait=1&spp=4", kScene, "text/plain");
  ASSERT_TRUE(waited);
  ASSERT_EQ(waited->status, 200);
  EXPECT_EQ(status_of(*c, waited->get_header_value("X-Job-Id"))["priority"], "interactive");
  // Named, it wins over the wait's default.
  auto named = c->Post("/render?wait=1&spp=5&priority=batch", kScene, "text/plain");
  ASSERT_TRUE(named);
  EXPECT_EQ(status_of(*c, named->get_header_value("X-Job-Id"))["priority"], "batch");
  auto bad = c->Post("/render?priority=urgent", kScene, "text/plain");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  EXPECT_EQ(error_of(bad)["path"], "priority");
  EXPECT_NE(error_of(bad)["message"].get<std::string>().find("interactive"), std::string::npos);
  wait_final(*c, batch);
}

TEST(ServerPriority, ItDoesNotSplitTheCache) {
  TestServer server;
  auto c = server.client();
  auto first = c->Post("/render?wait=1&spp=2&priority=batch", kScene, "text/plain");
  ASSERT_TRUE(first);
  ASSERT_EQ(first->status, 200);
  auto second = c->Post("/render?wait=1&spp=2&priority=interactive", kScene, "text/plain");
  ASSERT_TRUE(second);
  EXPECT_EQ(second->get_header_value("X-Cache"), "hit");
  EXPECT_EQ(second->get_header_value("ETag"), first->get_header_value("ETag"));
}

// A client at its limit of 4 rendering jobs queues the rest: an interactive job sent last is
// the next to start, ahead of earlier normal and batch ones.
TEST(ServerPriority, AHigherClassStartsFirstWhateverItsArrival) {
  Settings s = test_settings();
  s.workers = 1;
  TestServer server(s);
  auto c = server.client();
  std::vector<std::string> ids;
  for (int i = 0; i < 4; ++i) ids.push_back(submit(*c, kLong + std::string("&seed=") + std::to_string(i)));
  for (const std::string& id : ids) wait_running(*c, id);
  // (Seeds of their own: a job of an image being rendered would wait for that render.)
  const std::string batch = submit(*c, kLong + std::string("&priority=batch&seed=8"));
  const std::string normal = submit(*c, kLong + std::string("&seed=9"));
  const std::string interactive = submit(*c, kLong + std::string("&priority=interactive&seed=7"));
  EXPECT_EQ(status_of(*c, interactive)["queue_position"], 1);
  EXPECT_EQ(status_of(*c, normal)["queue_position"], 2);
  EXPECT_EQ(status_of(*c, batch)["queue_position"], 3);
  EXPECT_EQ(code_of(c->Delete("/jobs/" + ids[0])), 200);
  EXPECT_NE(wait_running(*c, interactive)["state"], "queued");
  EXPECT_EQ(status_of(*c, batch)["state"], "queued");
  for (const std::string& id : ids) c->Delete("/jobs/" + id);
  for (const std::string& id : {batch, normal, interactive}) c->Delete("/jobs/" + id);
}

httplib::Result post_keyed(httplib::Client& c, const std::string& key, const std::string& q = "spp=2",
                           const std::string& body = kScene) {
  return c.Post(query("/render", q), {{"Idempotency-Key", key}}, body, "text/plain");
}

TEST(ServerIdempotency, TheSameKeyGivesTheSameJobPerClient) {
  TestServer server;
  auto alice = server.client("alice-token");
  auto first = post_keyed(*alice, "4f1c-retry-1", kLong);
  ASSERT_TRUE(first);
  ASSERT_EQ(first->status, 202) << first->body;
  EXPECT_FALSE(first->has_header("Idempotent-Replayed"));
  const std::string id = json_of(first)["id"];
  auto again = post_keyed(*alice, "4f1c-retry-1", kLong);
  ASSERT_TRUE(again);
  ASSERT_EQ(again->status, 202) << again->body;
  EXPECT_EQ(json_of(again)["id"], id);
  EXPECT_EQ(again->get_header_value("Idempotent-Replayed"), "true");
  EXPECT_EQ(json_of(alice->Get("/jobs"))["jobs"].size(), 1u);  // not a second render
  // Keys are per client: bob's same key is bob's own job.
  auto bob = server.client("bob-token");
  auto bobs = post_keyed(*bob, "4f1c-retry-1", kLong);
  ASSERT_TRUE(bobs);
  ASSERT_EQ(bobs->status, 202);
  EXPECT_NE(json_of(bobs)["id"], id);
  alice->Delete("/jobs/" + id);
  bob->Delete("/jobs/" + json_of(bobs)["id"].get<std::string>());
}

TEST(ServerIdempotency, AKeyWithAnotherRequestIs422AndBadKeysAre400) {
  TestServer server;
  auto c = server.client();
  auto first = post_keyed(*c, "k-1");
  ASSERT_TRUE(first);
  ASSERT_EQ(first->status, 202);
  const std::string id = json_of(first)["id"];
  auto other = post_keyed(*c, "k-1", "spp=3");
  ASSERT_TRUE(other);
  EXPECT_EQ(other->status, 422);
  EXPECT_EQ(error_of(other)["code"], "idempotency_key_reused");
  EXPECT_NE(error_of(other)["message"].get<std::string>().find(id), std::string::npos);
  // The order of the options is not another request; waiting for the answer is not either.
  auto waited = post_keyed(*c, "k-1", "wait=1&spp=2");
  ASSERT_TRUE(waited);
  EXPECT_EQ(waited->status, 200);
  EXPECT_EQ(waited->get_header_value("X-Job-Id"), id);
  EXPECT_EQ(waited->get_header_value("Idempotent-Replayed"), "true");
  for (const std::string& key : {std::string(256, 'a'), std::string("two words")}) {
    auto bad = post_keyed(*c, key);
    ASSERT_TRUE(bad);
    EXPECT_EQ(bad->status, 400);
    EXPECT_EQ(error_of(bad)["code"], "invalid_idempotency_key");
  }
  auto longest = post_keyed(*c, std::string(255, 'b'));
  ASSERT_TRUE(longest);
  EXPECT_EQ(longest->status, 202);
  // An empty key (which the HTTP library drops before any handler sees it) is refused too,
  // not taken for no key: with or without white space, in any case.
  for (const std::string line : {"Idempotency-Key:", "idempotency-key: \t "}) {
    RawConnection conn(server.port());
    ASSERT_TRUE(conn.send(scene_post("Content-Type: text/plain\r\n" + line + "\r\n", kScene)));
    auto r = conn.read_response();
    ASSERT_TRUE(r) << line;
    EXPECT_EQ(r->status, 400) << line;
    EXPECT_EQ(Json::parse(r->body, nullptr, false)["error"]["code"], "invalid_idempotency_key")
        << line << r->body;
  }
}

TEST(ServerRestart, IdempotencyKeysOutliveARestart) {
  TempDir dir;
  Settings s = test_settings();
  s.results_dir = dir.path.string();
  std::string id;
  {
    TestServer server(s);
    auto r = post_keyed(*server.client(), "restart-key", "wait=1&spp=2");
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200);
    id = r->get_header_value("X-Job-Id");
  }
  TestServer server(s);
  auto again = post_keyed(*server.client(), "restart-key", "spp=2");
  ASSERT_TRUE(again);
  ASSERT_EQ(again->status, 202);
  EXPECT_EQ(json_of(again)["id"], id);
  EXPECT_EQ(json_of(again)["state"], "done");
  EXPECT_EQ(again->get_header_value("Idempotent-Replayed"), "true");
}

}  // namespace
}  // namespace rayfarm::server
