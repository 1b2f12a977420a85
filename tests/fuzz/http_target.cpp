// Fuzz target for rayfarmd's request path: an in-process server on a loopback port gets the
// input as raw bytes on a fresh connection. A 500 answer or a dead server is a finding.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>

#include "http_api.h"
#include "service.h"
#include "targets.h"

namespace rayfarm::fuzz {
namespace {

struct Fixture {
  std::unique_ptr<server::Service> service;
  std::unique_ptr<server::HttpApi> api;
  std::thread thread;
  int port = 0;

  Fixture() {
    server::Settings s;
    s.workers = 1;
    s.max_pixels = 64 * 64;
    s.max_spp = 4;
    s.max_depth = 4;
    s.max_objects = 64;
    s.max_body_bytes = 64 * 1024;
    s.job_timeout = 5;
    s.access_log = false;
    s.samples_dir = RAYFARM_SOURCE_DIR "/scenes";
    service = std::make_unique<server::Service>(s);
    api = std::make_unique<server::HttpApi>(*service);
    port = api->bind("127.0.0.1", 0);
    if (port <= 0) std::abort();
    thread = std::thread([this] { api->listen(); });
  }
};

Fixture& fixture() {
  static Fixture* f = new Fixture();  // lives for the process; the fuzzer exits without teardown
  return *f;
}

// Sends the bytes, half-closes, reads the answer (up to 2 s). Returns the status, 0 if none.
int round_trip(int port, const std::string& request) {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return -1;
  }
  size_t sent = 0;
  while (sent < request.size()) {
    ssize_t n = ::send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) break;
    sent += static_cast<size_t>(n);
  }
  ::shutdown(fd, SHUT_WR);
  std::string answer;
  char buf[4096];
  pollfd p{fd, POLLIN, 0};
  while (answer.size() < 16 && ::poll(&p, 1, 2000) > 0) {
    ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    answer.append(buf, static_cast<size_t>(n));
  }
  ::close(fd);
  int status = 0;
  if (answer.rfind("HTTP/1.", 0) == 0 && answer.size() >= 12) status = std::atoi(answer.c_str() + 9);
  return status;
}

}  // namespace

int http_request(const std::uint8_t* data, std::size_t size) {
  Fixture& f = fixture();
  int status = round_trip(f.port, std::string(reinterpret_cast<const char*>(data), size));
  if (status == -1 || status == 500) {
    std::fprintf(stderr, "fuzz property violated: server answered %d\n", status);
    std::abort();
  }
  // Let any render the input started finish, so that no worker is mid-job when the fuzzer
  // exits (its exit would pull globals from under a running render).
  for (int i = 0; i < 500; ++i) {
    auto health = f.service->health();
    if (health["running"] == 0 && health["queue_depth"] == 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  // The server must still answer a plain request.
  if (round_trip(f.port, "GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n") != 200) {
    std::fprintf(stderr, "fuzz property violated: /healthz failed after the input\n");
    std::abort();
  }
  return 0;
}

}  // namespace rayfarm::fuzz
