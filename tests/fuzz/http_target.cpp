// Fuzz target for rayfarmd's request path: an in-process server on a loopback port gets the
// input as raw bytes on a fresh connection. A 500 answer, a dead server or one that does not
// finish an input's requests and renders is a finding.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
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
    // The server's threads (and those they start) block the fuzzer's signals, which then go
    // to the fuzzing thread: cpp-httplib stops listening when a signal interrupts its accept.
    sigset_t fuzzer_signals, before;
    sigemptyset(&fuzzer_signals);
    for (int sig : {SIGALRM, SIGINT, SIGTERM, SIGUSR1, SIGUSR2}) sigaddset(&fuzzer_signals, sig);
    pthread_sigmask(SIG_BLOCK, &fuzzer_signals, &before);
    service = std::make_unique<server::Service>(s);
    api = std::make_unique<server::HttpApi>(*service);
    port = api->bind("127.0.0.1", 0);
    if (port <= 0) std::abort();
    thread = std::thread([this] { api->listen(); });
    pthread_sigmask(SIG_SETMASK, &before, nullptr);
    // The fuzzer ends with exit() while the server's threads live: stop them (as rayfarmd does
    // on SIGTERM) before exit destroys what they use. Exit handlers run in reverse order of
    // registration, so this runs before the destructors of everything built so far; statics
    // first built later (in cpp-httplib, for one) are destroyed before it, which is safe only
    // because every input ends with the server idle.
    instance = this;
    std::atexit([] { instance->stop(); });
  }

  void stop() {
    service->shutdown();
    api->stop();
    thread.join();
    api.reset();
    service.reset();
  }

  // No connection being served, no job queued or running.
  bool idle() const {
    if (api->open_connections() != 0) return false;
    auto health = service->health();
    return health["running"] == 0 && health["queue_depth"] == 0;
  }

  static inline Fixture* instance = nullptr;
};

Fixture& fixture() {
  static Fixture* f = new Fixture();
  return *f;
}

// Waits until the server is idle; false if it is still busy after `limit`.
bool settle(const Fixture& f, std::chrono::seconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!f.idle()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return true;
}

// The fuzzer's SIGALRM (its -timeout clock) interrupts this thread's calls: they resume.
int poll_for(int fd, short events, std::chrono::steady_clock::time_point deadline) {
  pollfd p{fd, events, 0};
  for (;;) {
    auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    int r = ::poll(&p, 1, static_cast<int>(std::max<long long>(0, left.count())));
    if (r >= 0 || errno != EINTR) return r;
  }
}

bool connect_loopback(int fd, int port) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) return true;
  if (errno != EINTR) return false;
  // An interrupted connect goes on by itself; its outcome is the socket's error.
  if (poll_for(fd, POLLOUT, std::chrono::steady_clock::now() + std::chrono::seconds(2)) <= 0) {
    errno = ETIMEDOUT;
    return false;
  }
  int error = 0;
  socklen_t len = sizeof error;
  if (::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &len) != 0) return false;
  errno = error;
  return error == 0;
}

// Sends the bytes, half-closes, reads the answer (up to 2 s). Returns the status, 0 if none,
// -1 if the connection failed; `trouble` says what went wrong.
int round_trip(int port, const std::string& request, std::string& trouble) {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (!connect_loopback(fd, port)) {
    trouble = std::string("connect: ") + std::strerror(errno);
    ::close(fd);
    return -1;
  }
  size_t sent = 0;
  while (sent < request.size()) {
    ssize_t n = ::send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    sent += static_cast<size_t>(n);
  }
  ::shutdown(fd, SHUT_WR);
  std::string answer;
  char buf[4096];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  trouble = "no answer within 2 s";
  while (answer.size() < 16 && poll_for(fd, POLLIN, deadline) > 0) {
    ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      trouble = n == 0 ? "closed without an answer" : std::string("recv: ") + std::strerror(errno);
      break;
    }
    answer.append(buf, static_cast<size_t>(n));
  }
  ::close(fd);
  int status = 0;
  if (answer.rfind("HTTP/1.", 0) == 0 && answer.size() >= 12) status = std::atoi(answer.c_str() + 9);
  if (status != 0) trouble = "answered " + std::to_string(status);
  return status;
}

}  // namespace

int http_request(const std::uint8_t* data, std::size_t size) {
  // Longer than the fuzzer's -timeout, which then reports the input as a hang.
  constexpr std::chrono::seconds kSettleLimit{30};
  Fixture& f = fixture();
  std::string trouble;
  int status = round_trip(f.port, std::string(reinterpret_cast<const char*>(data), size), trouble);
  if (status == -1 || status == 500) {
    std::fprintf(stderr, "fuzz property violated: %s\n", trouble.c_str());
    std::abort();
  }
  // The input's requests (those after the answer read, and the logging of each) and the
  // renders it started end here, not during the next input or the fuzzer's exit.
  if (!settle(f, kSettleLimit)) {
    std::fprintf(stderr, "fuzz property violated: the server is still busy %llds after the input\n",
                 static_cast<long long>(kSettleLimit.count()));
    std::abort();
  }
  // The server must still answer a plain request.
  if (round_trip(f.port, "GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n", trouble) != 200) {
    std::fprintf(stderr, "fuzz property violated: /healthz failed after the input: %s\n",
                 trouble.c_str());
    std::abort();
  }
  if (!settle(f, kSettleLimit)) {
    std::fprintf(stderr, "fuzz property violated: /healthz still busy %llds after its answer\n",
                 static_cast<long long>(kSettleLimit.count()));
    std::abort();
  }
  return 0;
}

}  // namespace rayfarm::fuzz
