// Where Redis is and how to log in: `redis://[user@]host[:port][/db]` or `unix:///path`.
// The password never travels in the URL (it would show in `ps`, shell history and logs): it
// comes from a file (--redis-password-file) or the environment (RAYFARM_REDIS_PASSWORD).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "redis_error.h"

namespace rayfarm::farm {

struct RedisUrl {
  enum class Transport { Tcp, Unix };
  Transport transport = Transport::Tcp;
  std::string host;  // Tcp
  int port = 6379;   // Tcp
  std::string path;  // Unix: the socket
  std::string user;  // ACL user; empty = the default user
  int db = 0;        // SELECTed after connecting

  // The URL back, without secrets (there are none in it), for logs and /healthz.
  std::string to_string() const;
};

Result<RedisUrl> parse_redis_url(std::string_view url);

// The password: the file's content (one line; a final newline is dropped) when `file` is given,
// else the environment value, else none (empty). Both at once is an error: no silent choice.
// `env` is the value of RAYFARM_REDIS_PASSWORD (nullptr when unset), passed in for the tests.
Result<std::string> load_redis_password(const std::optional<std::string>& file, const char* env);

}  // namespace rayfarm::farm
