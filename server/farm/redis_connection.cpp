#include "redis_connection.h"
#include "socket_peer.h"

#include <hiredis.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace rayfarm::farm {
namespace {

using std::chrono::milliseconds;
using Clock = std::chrono::steady_clock;

timeval to_timeval(milliseconds ms) {
  timeval tv{};
  tv.tv_sec = static_cast<time_t>(ms.count() / 1000);
  tv.tv_usec = static_cast<suseconds_t>((ms.count() % 1000) * 1000);
  return tv;
}

// Redis's messages end in a full stop; one is not wanted before "; next attempt".
std::string without_full_stop(std::string text) {
  if (!text.empty() && text.back() == '.') text.pop_back();
  return text;
}

bool setup_error(ErrorKind k) {
  return k == ErrorKind::Config || k == ErrorKind::Auth || k == ErrorKind::Build ||
         k == ErrorKind::NoPerm;
}

}  // namespace

Connection::Connection(ConnectOptions options)
    : options_(std::move(options)), jitter_(std::random_device{}()) {}

Connection::~Connection() { disconnect(); }

void Connection::disconnect() {
  if (ctx_) redisFree(ctx_);
  ctx_ = nullptr;
}

bool Connection::closed_by_peer() const { return ctx_ && socket_closed_by_peer(ctx_->fd); }

Error Connection::context_error(const char* what) {
  const int saved_errno = errno;
  ErrorKind kind = ErrorKind::ConnectionLost;
  std::string detail = ctx_ ? ctx_->errstr : "no context";
  if (ctx_ && ctx_->err == REDIS_ERR_PROTOCOL) kind = ErrorKind::Protocol;
  if (ctx_ && ctx_->err == REDIS_ERR_IO &&
      (saved_errno == EAGAIN || saved_errno == EWOULDBLOCK || saved_errno == ETIMEDOUT))
    kind = ErrorKind::Timeout;
  disconnect();
  schedule_retry();
  return Error{kind, std::string(what) + " " + options_.url.to_string() + ": " + detail};
}

void Connection::schedule_retry() {
  ++failures_;
  const auto initial = std::max<milliseconds::rep>(1, options_.backoff_initial.count());
  const int doublings = std::min(failures_ - 1, 20);
  const auto d = std::min<milliseconds::rep>(options_.backoff_max.count(), initial << doublings);
  std::uniform_int_distribution<milliseconds::rep> pick(d / 2, d);
  next_attempt_ = Clock::now() + milliseconds(pick(jitter_));
}

Status Connection::set_timeout(milliseconds t) {
  if (redisSetTimeout(ctx_, to_timeval(t)) != REDIS_OK)
    return context_error("setting the timeout on");
  return Ok{};
}

Status Connection::connect() {
  disconnect();
  const timeval tv = to_timeval(options_.connect_timeout);
  const RedisUrl& u = options_.url;
  ctx_ = u.transport == RedisUrl::Transport::Unix
             ? redisConnectUnixWithTimeout(u.path.c_str(), tv)
             : redisConnectWithTimeout(u.host.c_str(), u.port, tv);
  if (!ctx_) {
    schedule_retry();
    return Error{ErrorKind::Unavailable, "cannot allocate a Redis context"};
  }
  if (ctx_->err) {
    Error e = context_error("cannot connect to");
    e.kind = ErrorKind::Unavailable;
    return e;
  }
  if (u.transport == RedisUrl::Transport::Tcp) redisEnableKeepAlive(ctx_);
  if (auto s = set_timeout(options_.command_timeout); !s) {
    Error e = s.error();
    e.kind = ErrorKind::Unavailable;
    return e;
  }
  connecting_ = true;
  auto fail = [this](Error e) -> Status {
    connecting_ = false;
    if (e.outcome_unknown()) e.kind = ErrorKind::Unavailable;
    if (setup_error(e.kind)) refused_ = e.message;
    if (ctx_) {  // an error reply; a lost connection was already dropped and scheduled
      disconnect();
      schedule_retry();
    }
    return e;
  };
  if (!options_.password.empty() || !u.user.empty()) {
    std::vector<std::string_view> auth{"AUTH"};
    if (!u.user.empty()) auth.push_back(u.user);
    auth.push_back(options_.password);
    if (auto r = command(auth); !r) {
      // Refusals of the credentials are the settings' to fix, whatever their first word: a
      // password given to a Redis that has none answers "ERR AUTH <password> called without
      // any password configured".
      Error e = r.error();
      if (e.message.starts_with("ERR AUTH") || e.message.starts_with("ERR Client sent AUTH") ||
          e.message.starts_with("ERR invalid password"))
        e.kind = ErrorKind::Auth;
      return fail(e);
    }
  }
  if (u.db != 0) {
    const std::string db = std::to_string(u.db);
    if (auto r = command({"SELECT", db}); !r) {
      Error e = r.error();  // "ERR DB index is out of range": the URL's number
      if (!e.transient()) {
        e.kind = ErrorKind::Config;
        e.message += " (the URL's database " + db + ")";
      }
      return fail(e);
    }
  }
  if (options_.on_connect)
    if (auto s = options_.on_connect(*this); !s) return fail(s.error());
  connecting_ = false;
  failures_ = 0;
  refused_.clear();
  ++connects_;
  return Ok{};
}

Status Connection::ensure_connected() {
  if (ctx_) return Ok{};
  if (connecting_)
    return Error{ErrorKind::Unavailable, "the connection was lost while setting it up"};
  const auto now = Clock::now();
  if (failures_ > 0 && now < next_attempt_) {
    const auto wait = std::chrono::duration_cast<milliseconds>(next_attempt_ - now).count();
    // Refused at setup (another build, a wrong password): that reason, not "unavailable".
    if (!refused_.empty())
      return Error{ErrorKind::Unavailable,
                   "the farm at " + options_.url.to_string() + " refused this node: " +
                       without_full_stop(refused_) + "; next attempt in " +
                       std::to_string(wait) + " ms"};
    return Error{ErrorKind::Unavailable, "Redis at " + options_.url.to_string() +
                                             " is unavailable; next attempt in " +
                                             std::to_string(wait) + " ms"};
  }
  return connect();
}

Status Connection::wait_connected(milliseconds max_wait) {
  const auto deadline = Clock::now() + max_wait;
  for (;;) {
    Status s = ensure_connected();
    if (s || setup_error(s.error().kind) || Clock::now() >= deadline) return s;
    std::this_thread::sleep_until(
        std::min(deadline, std::max(next_attempt_, Clock::now() + milliseconds(1))));
  }
}

Result<Reply> Connection::run(std::span<const std::string_view> argv) {
  if (auto s = ensure_connected(); !s) return s.error();
  std::vector<const char*> ptrs;
  std::vector<std::size_t> lens;
  ptrs.reserve(argv.size());
  lens.reserve(argv.size());
  for (std::string_view a : argv) {
    ptrs.push_back(a.data());
    lens.push_back(a.size());
  }
  errno = 0;
  auto* raw = static_cast<redisReply*>(
      redisCommandArgv(ctx_, static_cast<int>(argv.size()), ptrs.data(), lens.data()));
  if (!raw) return context_error("lost the connection to");
  Reply reply(raw);
  if (reply.type() == ReplyView::Type::ErrorReply)
    return Error{classify_error_reply(reply.str()), std::string(reply.str())};
  return reply;
}

Result<Reply> Connection::command(std::span<const std::string_view> argv) {
  const auto deadline = Clock::now() + options_.loading_wait;
  for (;;) {
    Result<Reply> r = run(argv);
    if (r || r.error().kind != ErrorKind::Loading || Clock::now() >= deadline) return r;
    std::this_thread::sleep_for(milliseconds(100));
  }
}

Result<Reply> Connection::command(const std::vector<std::string>& argv) {
  std::vector<std::string_view> views(argv.begin(), argv.end());
  return command(std::span<const std::string_view>(views));
}

Result<Reply> Connection::command(std::span<const std::string_view> argv, milliseconds timeout) {
  if (auto s = ensure_connected(); !s) return s.error();
  if (auto s = set_timeout(timeout); !s) return s.error();
  Result<Reply> r = command(argv);
  if (ctx_)
    if (auto s = set_timeout(options_.command_timeout); !s) return s.error();
  return r;
}

Result<std::optional<Reply>> Connection::next_message(milliseconds wait) {
  if (!ctx_) return Error{ErrorKind::ConnectionLost, "not subscribed: no connection"};
  const auto deadline = Clock::now() + wait;
  for (;;) {
    void* raw = nullptr;
    // A reply already read into hiredis's buffer comes first: poll() cannot see it.
    if (redisGetReplyFromReader(ctx_, &raw) != REDIS_OK)
      return context_error("reading a message from");
    if (raw) return std::optional<Reply>(Reply(static_cast<redisReply*>(raw)));
    const auto left = std::chrono::duration_cast<milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return std::optional<Reply>();
    pollfd p{ctx_->fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno != EINTR) return context_error("waiting for a message from");
    if (ready <= 0) continue;
    errno = 0;
    if (redisBufferRead(ctx_) != REDIS_OK) return context_error("reading a message from");
  }
}

Result<std::vector<Result<Reply>>> Connection::pipeline(
    const std::vector<std::vector<std::string>>& cmds) {
  if (auto s = ensure_connected(); !s) return s.error();
  for (const auto& argv : cmds) {
    std::vector<const char*> ptrs;
    std::vector<std::size_t> lens;
    for (const std::string& a : argv) {
      ptrs.push_back(a.data());
      lens.push_back(a.size());
    }
    if (redisAppendCommandArgv(ctx_, static_cast<int>(argv.size()), ptrs.data(), lens.data()) !=
        REDIS_OK)
      return context_error("queueing a pipeline for");
  }
  std::vector<Result<Reply>> out;
  out.reserve(cmds.size());
  for (std::size_t i = 0; i < cmds.size(); ++i) {
    void* raw = nullptr;
    errno = 0;
    if (redisGetReply(ctx_, &raw) != REDIS_OK || !raw)
      return context_error("lost the connection to");
    Reply reply(static_cast<redisReply*>(raw));
    if (reply.type() == ReplyView::Type::ErrorReply)
      out.emplace_back(Error{classify_error_reply(reply.str()), std::string(reply.str())});
    else
      out.emplace_back(std::move(reply));
  }
  return out;
}

// --- Pool ---

struct Pool::State {
  std::mutex mutex;
  std::condition_variable returned;
  ConnectOptions options;
  std::vector<std::unique_ptr<Connection>> connections;
  std::vector<std::size_t> idle;
  std::size_t size = 0;
};

Pool::Pool(ConnectOptions options, std::size_t size) : state_(std::make_unique<State>()) {
  state_->options = std::move(options);
  state_->size = std::max<std::size_t>(1, size);
  state_->connections.reserve(state_->size);
}

Pool::~Pool() = default;

std::size_t Pool::size() const { return state_->size; }

Result<Pool::Lease> Pool::acquire(milliseconds wait) {
  State& s = *state_;
  std::unique_lock lock(s.mutex);
  const bool got = s.returned.wait_for(
      lock, wait, [&] { return !s.idle.empty() || s.connections.size() < s.size; });
  if (!got)
    return Error{ErrorKind::Unavailable,
                 "all " + std::to_string(s.size) + " Redis connections are busy"};
  if (!s.idle.empty()) {
    const std::size_t i = s.idle.back();
    s.idle.pop_back();
    return Lease(this, i);
  }
  s.connections.push_back(std::make_unique<Connection>(s.options));
  return Lease(this, s.connections.size() - 1);
}

Connection& Pool::Lease::operator*() const {
  std::lock_guard lock(pool_->state_->mutex);
  return *pool_->state_->connections[index_];
}

Pool::Lease::~Lease() {
  if (!pool_) return;
  {
    std::lock_guard lock(pool_->state_->mutex);
    pool_->state_->idle.push_back(index_);
  }
  pool_->state_->returned.notify_one();
}

}  // namespace rayfarm::farm
