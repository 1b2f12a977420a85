#include "redis_error.h"

#include <string_view>

namespace rayfarm::farm {

const char* to_string(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::Config:
      return "config";
    case ErrorKind::Unavailable:
      return "unavailable";
    case ErrorKind::ConnectionLost:
      return "connection lost";
    case ErrorKind::Timeout:
      return "timeout";
    case ErrorKind::Protocol:
      return "protocol";
    case ErrorKind::Auth:
      return "auth";
    case ErrorKind::Oom:
      return "oom";
    case ErrorKind::NoPerm:
      return "noperm";
    case ErrorKind::NoGroup:
      return "nogroup";
    case ErrorKind::Busy:
      return "busy";
    case ErrorKind::Loading:
      return "loading";
    case ErrorKind::ReadOnly:
      return "readonly";
    case ErrorKind::Build:
      return "build";
    case ErrorKind::Reply:
      return "reply";
    case ErrorKind::Unexpected:
      return "unexpected";
  }
  return "?";
}

ErrorKind classify_error_reply(std::string_view message) {
  std::string_view word = message.substr(0, message.find(' '));
  if (word == "OOM") return ErrorKind::Oom;
  if (word == "NOPERM") return ErrorKind::NoPerm;
  if (word == "NOGROUP") return ErrorKind::NoGroup;
  if (word == "BUSY") return ErrorKind::Busy;
  if (word == "LOADING") return ErrorKind::Loading;
  if (word == "READONLY") return ErrorKind::ReadOnly;
  if (word == "WRONGPASS" || word == "NOAUTH") return ErrorKind::Auth;
  // A Redis at maxclients answers a new connection's first command so, then closes it.
  if (message.starts_with("ERR max number of clients")) return ErrorKind::Unavailable;
  // An error raised by a command inside a Function keeps the command's prefix.
  if (message.find("OOM command not allowed") != std::string_view::npos) return ErrorKind::Oom;
  return ErrorKind::Reply;
}

}  // namespace rayfarm::farm
