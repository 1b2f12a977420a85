// rayfarmd: the render service. SIGTERM/SIGINT stop intake, let running renders finish for
// the grace period, persist the rest, and exit cleanly.
#include <csignal>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <fstream>
#include <pthread.h>
#include <thread>
#include <unistd.h>

#include "http_api.h"
#include "service.h"
#include "settings.h"

namespace {

std::string default_samples_dir(const char* argv0) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path exe = fs::canonical("/proc/self/exe", ec);
  if (ec) exe = argv0;
  for (fs::path p : {exe.parent_path().parent_path() / "share/rayfarm/scenes",
                     fs::path(RAYFARM_SOURCE_SCENES)})
    if (fs::is_directory(p, ec)) return p.string();
  return {};
}

// `rayfarmd --make-tokens CLASS`: a roster line with a fresh token for each name of a class
// list (one per line, # comments), on standard output, for --tokens-file.
int make_tokens(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "rayfarmd: cannot read the class list %s\n", path.c_str());
    return 1;
  }
  std::printf("# rayfarmd --tokens-file: NAME TOKEN [max_jobs=N]; give each student their line\n");
  std::string line;
  while (std::getline(in, line)) {
    if (const size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::string name;
    if (words >> name) std::printf("%s %s\n", name.c_str(), rayfarm::server::new_token().c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace rayfarm::server;
  // Signals are taken by one thread with sigwait; every other thread has them blocked.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::signal(SIGPIPE, SIG_IGN);

  int exit_code = 0;
  auto settings = parse_settings(argc, argv, exit_code);
  if (!settings) return exit_code;
  if (settings->samples_dir.empty()) settings->samples_dir = default_samples_dir(argv[0]);
  if (!settings->make_tokens.empty()) return make_tokens(settings->make_tokens);

  std::unique_ptr<Service> service;
  try {
    service = std::make_unique<Service>(*settings);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rayfarmd: %s\n", e.what());
    return 1;
  }
  HttpApi api(*service);
  errno = 0;
  int port = api.bind(settings->host, settings->port);
  if (port < 0) {
    const int err = errno;
    std::fprintf(stderr, "rayfarmd: cannot listen on %s:%d: %s\n", settings->host.c_str(),
                 settings->port,
                 err == EADDRINUSE ? "the port is in use (is another rayfarmd running?)"
                 : err == EACCES   ? "permission denied (ports below 1024 need privileges)"
                 : err != 0        ? std::strerror(err)
                                   : "the address cannot be bound");
    return 1;
  }
  std::fprintf(stderr, "rayfarmd: listening on http://%s:%d (%d render workers, results %s)\n",
               settings->host.c_str(), port, service->health()["workers"].get<int>(),
               settings->results_dir.empty() ? "in memory" : settings->results_dir.c_str());

  if (!settings->redis.empty()) {
    // Whether the farm could be reached at start: a node that cannot answers 503 until then.
    const nlohmann::json redis = service->health()["redis"];
    const std::string node = redis.value("node", ""), status = redis.value("status", "");
    if (status == "ok")
      std::fprintf(stderr, "rayfarmd: farm node %s at %s\n", node.c_str(),
                   redis.value("url", "").c_str());
    else
      std::fprintf(stderr,
                   "rayfarmd: warning: farm node %s cannot reach %s (%s); it answers 503 until "
                   "it can\n",
                   node.c_str(), redis.value("url", "").c_str(),
                   redis.value("error", status).c_str());
  }
  const bool loopback = settings->host == "127.0.0.1" || settings->host == "localhost" ||
                        settings->host == "::1";
  if (!loopback && settings->tokens.empty() && settings->tokens_file.empty())
    std::fprintf(stderr,
                 "rayfarmd: warning: listening on %s with no tokens: every client behind one "
                 "proxy is one client (one quota, anyone may cancel anyone's job); give each "
                 "student a name with --tokens-file\n",
                 settings->host.c_str());
  if (!settings->tokens_file.empty())
    std::fprintf(stderr, "rayfarmd: roster %s: %zu names\n", settings->tokens_file.c_str(),
                 service->roster().size());

  std::thread signal_thread([&] {
    int sig = 0;
    // SIGHUP rereads the roster; SIGTERM and SIGINT stop.
    while (sigwait(&signals, &sig) == 0 && sig == SIGHUP) service->reload_roster();
    std::fprintf(stderr, "rayfarmd: %s: finishing running renders, then stopping\n",
                 sig == SIGTERM ? "SIGTERM" : "SIGINT");
    service->shutdown();
    api.stop();
  });
  bool ok = api.listen();
  if (!ok && !service->shutting_down()) {
    // listen failed on its own: wake the signal thread so it can end.
    kill(getpid(), SIGTERM);
  }
  signal_thread.join();
  std::fprintf(stderr, "rayfarmd: stopped\n");
  return 0;
}
