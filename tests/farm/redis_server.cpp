#include "redis_server.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace rayfarm::farm::test {

bool redis_required() {
  const char* v = std::getenv("RAYFARM_REQUIRE_REDIS");
  return v && std::string(v) == "1";
}

std::optional<std::string> RedisServer::binary() {
  const char* path = std::getenv("PATH");
  std::string p = path ? path : "/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= p.size()) {
    std::size_t end = p.find(':', start);
    if (end == std::string::npos) end = p.size();
    std::string candidate = p.substr(start, end - start) + "/redis-server";
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    start = end + 1;
  }
  return std::nullopt;
}

RedisServer::RedisServer(std::vector<std::string> extra) : extra_(std::move(extra)) {
  char tmpl[] = "/tmp/rft.XXXXXX";
  if (::mkdtemp(tmpl)) dir_ = tmpl;
}

RedisServer::~RedisServer() {
  kill9();
  if (!dir_.empty()) {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
}

RedisUrl RedisServer::url() const {
  RedisUrl u;
  u.transport = RedisUrl::Transport::Unix;
  u.path = socket();
  return u;
}

ConnectOptions RedisServer::options() const {
  ConnectOptions o;
  o.url = url();
  o.connect_timeout = std::chrono::milliseconds(1000);
  o.command_timeout = std::chrono::milliseconds(3000);
  o.backoff_initial = std::chrono::milliseconds(20);
  o.backoff_max = std::chrono::milliseconds(200);
  return o;
}

bool RedisServer::start() {
  // Writing to a killed server's socket raises SIGPIPE; rayfarmd ignores it (main.cpp), and so
  // must every program that uses a Connection.
  ::signal(SIGPIPE, SIG_IGN);
  auto bin = binary();
  if (!bin || dir_.empty()) return false;
  std::vector<std::string> args{*bin,
                                "--port",
                                "0",
                                "--unixsocket",
                                socket(),
                                "--unixsocketperm",
                                "700",
                                "--dir",
                                dir_,
                                "--save",
                                "",
                                "--appendonly",
                                "yes",
                                "--appendfsync",
                                "everysec",
                                "--daemonize",
                                "no",
                                "--logfile",
                                dir_ + "/redis.log"};
  args.insert(args.end(), extra_.begin(), extra_.end());
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::unlink(socket().c_str());
  const pid_t pid = ::fork();
  if (pid == 0) {
    int null = ::open("/dev/null", O_RDWR);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  if (pid < 0) return false;
  pid_ = pid;
  ConnectOptions o = options();
  o.loading_wait = std::chrono::milliseconds(5000);
  Connection c(o);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < deadline) {
    if (::access(socket().c_str(), F_OK) == 0 && c.connect()) {
      auto pong = c.command({"PING"});
      if (pong || pong.error().kind == ErrorKind::Auth) return true;  // up, with requirepass
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

void RedisServer::kill9() {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGKILL);
  int status = 0;
  ::waitpid(pid_, &status, 0);
  pid_ = -1;
}

double RedisServer::cpu_seconds() const {
  std::ifstream in("/proc/" + std::to_string(pid_) + "/stat");
  std::string line;
  std::getline(in, line);
  if (line.rfind(')') == std::string::npos) return 0;
  std::istringstream rest(line.substr(line.rfind(')') + 2));
  std::string field;
  unsigned long long utime = 0, stime = 0;
  for (int i = 3; i <= 15 && rest >> field; ++i) {
    if (i == 14) utime = std::stoull(field);
    if (i == 15) stime = std::stoull(field);
  }
  return static_cast<double>(utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

}  // namespace rayfarm::farm::test
