// Errors of the Redis layer as values (the project's style: nothing here throws or exits).
// The kinds are the ones a caller must tell apart: a lost connection or a timeout leaves the
// outcome of the command unknown (retry only what is idempotent); OOM means Redis is full (the
// server answers 503); LOADING is retried inside Connection; the rest are reported.
#pragma once

#include <string>
#include <utility>
#include <variant>

namespace rayfarm::farm {

enum class ErrorKind {
  Config,         // a bad URL, an unreadable password file: fix the settings
  Unavailable,    // not connected (refused, or waiting for the next reconnect attempt)
  ConnectionLost, // I/O error or EOF during a command: its outcome is unknown
  Timeout,        // no reply in time: the outcome is unknown, the connection is dropped
  Protocol,       // a reply hiredis could not parse; the connection is dropped
  Auth,           // AUTH refused (WRONGPASS) or needed (NOAUTH)
  Oom,            // "OOM command not allowed": Redis is at maxmemory
  NoPerm,         // the ACL user may not run the command
  NoGroup,        // the stream or its consumer group is gone (flushed)
  Busy,           // a script is running past busy-reply-threshold
  Loading,        // Redis is still loading its data set (retried until a deadline)
  ReadOnly,       // talking to a replica
  Build,          // the farm runs another build: this node must not join
  Reply,          // any other error reply
  Unexpected,     // a reply of an unexpected shape (a bug on one side)
};

const char* to_string(ErrorKind kind);

struct Error {
  ErrorKind kind = ErrorKind::Reply;
  std::string message;

  // The command may or may not have run: only an idempotent command may be repeated blindly.
  bool outcome_unknown() const {
    return kind == ErrorKind::ConnectionLost || kind == ErrorKind::Timeout ||
           kind == ErrorKind::Protocol;
  }
  // Worth trying again later (after a reconnect or a pause), as opposed to a setup error.
  bool transient() const {
    return outcome_unknown() || kind == ErrorKind::Unavailable || kind == ErrorKind::Busy ||
           kind == ErrorKind::Loading || kind == ErrorKind::Oom;
  }
};

// The kind of an error reply, from its first word (Redis's convention: "OOM command not ...").
ErrorKind classify_error_reply(std::string_view message);

struct Ok {};

// A value or an Error (std::expected is C++23).
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}
  Result(Error error) : v_(std::move(error)) {}

  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }
  T& value() { return std::get<0>(v_); }
  const T& value() const { return std::get<0>(v_); }
  T& operator*() { return value(); }
  const T& operator*() const { return value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  const Error& error() const { return std::get<1>(v_); }

 private:
  std::variant<T, Error> v_;
};

using Status = Result<Ok>;

}  // namespace rayfarm::farm
