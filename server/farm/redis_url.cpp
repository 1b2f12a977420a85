#include "redis_url.h"

#include <charconv>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace rayfarm::farm {
namespace {

Error config(std::string message) { return Error{ErrorKind::Config, std::move(message)}; }

bool parse_int(std::string_view s, int lo, int hi, int& out) {
  if (s.empty()) return false;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && end == s.data() + s.size() && out >= lo && out <= hi;
}

}  // namespace

std::string RedisUrl::to_string() const {
  if (transport == Transport::Unix) return "unix://" + path;
  std::string h = host.find(':') != std::string::npos ? "[" + host + "]" : host;
  std::string s = "redis://" + (user.empty() ? "" : user + "@") + h + ":" + std::to_string(port);
  if (db != 0) s += "/" + std::to_string(db);
  return s;
}

Result<RedisUrl> parse_redis_url(std::string_view url) {
  RedisUrl out;
  const std::string shown(url.substr(0, url.find('@')));  // never echo what follows a user
  if (url.starts_with("unix://")) {
    out.transport = RedisUrl::Transport::Unix;
    out.path = std::string(url.substr(7));
    if (out.path.empty() || out.path[0] != '/')
      return config("Redis URL " + shown +
                    ": a unix socket needs an absolute path (unix:///run/redis.sock)");
    if (out.path.find('?') != std::string::npos || out.path.find('@') != std::string::npos)
      return config("Redis URL unix://…: a unix socket URL takes no options and no user");
    if (out.path.size() > 107)
      return config("Redis URL: the unix socket path is longer than 107 bytes");
    return out;
  }
  if (url.starts_with("rediss://"))
    return config(
        "Redis URL: TLS (rediss://) is not supported by hiredis 0.14; use stunnel or a private "
        "network");
  if (!url.starts_with("redis://"))
    return config("Redis URL " + shown +
                  ": expected redis://[user@]host[:port][/db] or unix:///path");
  std::string_view rest = url.substr(8);
  std::string_view authority = rest.substr(0, rest.find('/'));
  std::string_view path = rest.size() > authority.size() ? rest.substr(authority.size() + 1) : "";
  if (auto at = authority.rfind('@'); at != std::string_view::npos) {
    std::string_view userinfo = authority.substr(0, at);
    if (userinfo.find(':') != std::string_view::npos)
      return config(
          "Redis URL: a password in the URL is refused (it would show in ps and logs); "
          "put it in --redis-password-file or RAYFARM_REDIS_PASSWORD");
    if (userinfo.empty()) return config("Redis URL: empty user before '@'");
    out.user = std::string(userinfo);
    authority = authority.substr(at + 1);
  }
  std::string_view host = authority, port;
  if (authority.starts_with("[")) {
    auto close = authority.find(']');
    if (close == std::string_view::npos) return config("Redis URL: unclosed '[' in the host");
    host = authority.substr(1, close - 1);
    std::string_view after = authority.substr(close + 1);
    if (!after.empty()) {
      if (after[0] != ':') return config("Redis URL: expected ':' after the IPv6 address");
      port = after.substr(1);
    }
  } else if (auto colon = authority.find(':'); colon != std::string_view::npos) {
    host = authority.substr(0, colon);
    port = authority.substr(colon + 1);
  }
  if (host.empty()) return config("Redis URL " + shown + ": no host");
  out.host = std::string(host);
  if (!port.empty() || authority.ends_with(":"))
    if (!parse_int(port, 1, 65535, out.port))
      return config("Redis URL: port '" + std::string(port) + "' is not a number in 1..65535");
  if (!path.empty() && !parse_int(path, 0, 1 << 20, out.db))
    return config("Redis URL: database '" + std::string(path) + "' is not a number");
  return out;
}

Result<std::string> load_redis_password(const std::optional<std::string>& file, const char* env) {
  if (file && env)
    return config("both --redis-password-file and RAYFARM_REDIS_PASSWORD are set; use one");
  if (!file) return std::string(env ? env : "");
  std::error_code ec;
  if (std::filesystem::is_directory(*file, ec))
    return config("the Redis password file " + *file + " is a folder, not a file");
  std::ifstream in(*file, std::ios::binary);
  if (!in) return config("cannot read the Redis password file " + *file);
  std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (s.ends_with("\n")) s.pop_back();
  if (s.ends_with("\r")) s.pop_back();
  if (s.empty()) return config("the Redis password file " + *file + " is empty");
  if (s.find_first_of("\r\n") != std::string::npos)
    return config("the Redis password file " + *file + " has more than one line");
  return s;
}

}  // namespace rayfarm::farm
