// A private redis-server for one test suite: started on a unix socket in a short temp dir
// (socket paths are limited to 107 bytes), AOF on, no TCP, killed at the end. The system
// Redis on 6379, if any, is never used.
#pragma once

#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

#include "redis_connection.h"

namespace rayfarm::farm::test {

class RedisServer {
 public:
  // `extra`: more redis-server arguments (e.g. {"--maxmemory", "2mb"}).
  explicit RedisServer(std::vector<std::string> extra = {});
  ~RedisServer();
  RedisServer(const RedisServer&) = delete;
  RedisServer& operator=(const RedisServer&) = delete;

  // The redis-server binary on PATH, if any.
  static std::optional<std::string> binary();

  // Starts it (with the same dir, so the AOF is replayed) and waits until it answers PING.
  bool start();
  // SIGKILL, as a crash: nothing is flushed beyond what the AOF already has.
  void kill9();
  bool running() const { return pid_ > 0; }
  int pid() const { return pid_; }
  // CPU time (user + system) the server has used so far, in seconds (for the benchmarks).
  double cpu_seconds() const;

  const std::string& dir() const { return dir_; }
  std::string socket() const { return dir_ + "/r.sock"; }
  RedisUrl url() const;
  ConnectOptions options() const;

 private:
  std::vector<std::string> extra_;
  std::string dir_;
  int pid_ = -1;
};

// In a test's SetUp: skip when redis-server is missing, or fail when RAYFARM_REQUIRE_REDIS=1.
#define RAYFARM_REQUIRE_REDIS_SERVER()                                                       \
  do {                                                                                       \
    if (!::rayfarm::farm::test::RedisServer::binary()) {                                     \
      if (::rayfarm::farm::test::redis_required())                                           \
        FAIL() << "redis-server is not on PATH and RAYFARM_REQUIRE_REDIS=1";                 \
      GTEST_SKIP() << "redis-server is not on PATH (apt-get install redis-server); skipped"; \
    }                                                                                        \
  } while (0)

bool redis_required();

}  // namespace rayfarm::farm::test
