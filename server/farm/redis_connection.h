// One synchronous hiredis connection, for one thread at a time (hiredis contexts have no
// locking: a node gives each of its threads its own Connection, and HTTP threads lease one
// from a Pool).
//
// Why this wrapper and not raw hiredis 0.14:
//  * After any I/O error, EOF or timeout a hiredis context is dead. The context is dropped and
//    the next command reconnects, no sooner than a capped exponential backoff with jitter
//    allows (so a Redis outage does not meet a thundering herd); every (re)connect re-applies
//    the socket timeout, AUTH and SELECT, which hiredis's own reconnect does not replay, then
//    runs `on_connect` (the farm loads its Functions and creates its consumer group there).
//  * A lost connection or a timeout leaves the command's outcome unknown: it is reported,
//    never retried here (the farm's Functions are idempotent, so callers may repeat them).
//    LOADING replies (Redis replaying its AOF) are retried: the command did not run.
//  * Commands go as argv with lengths (binary-safe), never through printf-style formats.
//  * Errors are values (ErrorKind), error replies included.
//  * hiredis writes with write(2): a program using a Connection must ignore SIGPIPE, or a write
//    to a dead server kills it (rayfarmd does, in main.cpp).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <memory>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "redis_error.h"
#include "redis_reply.h"
#include "redis_url.h"

struct redisContext;

namespace rayfarm::farm {

class Connection;

struct ConnectOptions {
  RedisUrl url;
  std::string password;  // empty: no AUTH
  std::chrono::milliseconds connect_timeout{2000};
  std::chrono::milliseconds command_timeout{5000};
  // How long LOADING replies are retried before the error is returned.
  std::chrono::milliseconds loading_wait{30000};
  // Reconnect delays: initial, doubled after each failure up to max; each drawn in [d/2, d].
  std::chrono::milliseconds backoff_initial{100};
  std::chrono::milliseconds backoff_max{5000};
  // Runs after every successful connect (AUTH and SELECT done); an error drops the connection.
  std::function<Status(Connection&)> on_connect;
};

class Connection {
 public:
  explicit Connection(ConnectOptions options);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  // One attempt now, whatever the backoff says.
  Status connect();
  // Connected, or one attempt if the backoff allows it now; else Unavailable at once (an HTTP
  // thread must not sleep through an outage).
  Status ensure_connected();
  // Retries with the backoff until connected or `max_wait` passed (for loops that have nothing
  // else to do). Setup errors (Config, Auth, Build, NoPerm) end the wait at once.
  Status wait_connected(std::chrono::milliseconds max_wait);
  bool connected() const { return ctx_ != nullptr; }
  void disconnect();
  // Whether Redis has closed this idle connection (its idle `timeout`, a proxy or NAT that
  // drops quiet connections): its end of file is waiting to be read. A look, no wait.
  bool closed_by_peer() const;

  // An error reply comes back as an Error (its kind from its first word), not as a Reply.
  Result<Reply> command(std::span<const std::string_view> argv);
  Result<Reply> command(std::initializer_list<std::string_view> argv) {
    return command(std::span<const std::string_view>(argv.begin(), argv.size()));
  }
  Result<Reply> command(const std::vector<std::string>& argv);
  // With a longer socket timeout for this command (a blocking read: it must exceed BLOCK).
  Result<Reply> command(std::span<const std::string_view> argv, std::chrono::milliseconds timeout);

  // Pipelining: every command is written, then every reply read, in one round trip. Error
  // replies are per command; a connection error fails the whole batch (outcomes unknown).
  Result<std::vector<Result<Reply>>> pipeline(const std::vector<std::vector<std::string>>& cmds);

  // After SUBSCRIBE (sent with command()): the next message Redis pushes, waiting up to
  // `wait`; an empty optional when none came. Unlike a socket timeout, an empty wait leaves
  // the connection usable.
  Result<std::optional<Reply>> next_message(std::chrono::milliseconds wait);

  const ConnectOptions& options() const { return options_; }
  // Successful connects so far (the first one included): a metric, and for the tests.
  std::uint64_t connects() const { return connects_; }

 private:
  Result<Reply> run(std::span<const std::string_view> argv);
  Error context_error(const char* what);
  void schedule_retry();
  Status set_timeout(std::chrono::milliseconds t);

  ConnectOptions options_;
  redisContext* ctx_ = nullptr;
  bool connecting_ = false;
  int failures_ = 0;
  std::chrono::steady_clock::time_point next_attempt_{};
  std::uint64_t connects_ = 0;
  std::string refused_;  // the last setup error (Build, Auth, ...) until a connect succeeds
  std::minstd_rand jitter_;
};

// A few connections shared by threads that each need one briefly (HTTP handlers). A Lease
// gives a connection to one thread and returns it when it goes out of scope. Connections are
// made lazily, up to `size`.
class Pool {
 public:
  class Lease {
   public:
    Lease(Lease&& other) noexcept : pool_(other.pool_), index_(other.index_) {
      other.pool_ = nullptr;
    }
    Lease& operator=(Lease&&) = delete;
    ~Lease();
    Connection& operator*() const;
    Connection* operator->() const { return &**this; }

   private:
    friend class Pool;
    Lease(Pool* pool, std::size_t index) : pool_(pool), index_(index) {}
    Pool* pool_;
    std::size_t index_;
  };

  Pool(ConnectOptions options, std::size_t size);
  ~Pool();
  // Unavailable when every connection stayed leased for `wait`.
  Result<Lease> acquire(std::chrono::milliseconds wait);
  std::size_t size() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace rayfarm::farm
