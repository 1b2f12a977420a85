// The class roster: who may use the server, by name. A tokens file has one person per line,
// `NAME TOKEN [max_jobs=N]`, with `#` comments; rayfarmd reads it at start and again on
// SIGHUP (a file with errors leaves the roster it had). Jobs belong to names, fair sharing
// and limits go by name, and the access log says who asked.
#pragma once

#include <memory>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <string>
#include <unordered_map>
#include <vector>

namespace rayfarm::server {

struct RosterEntry {
  std::string name;
  int max_jobs = 0;  // jobs queued or running at once; 0: the server's --max-jobs-per-client
};

class Roster {
 public:
  // Reads `path`. On errors (each "PATH:LINE: message") the roster is unchanged.
  bool load(const std::string& path, std::vector<std::string>* errors);
  // Parses a tokens file's text; nullopt with the errors.
  static std::optional<std::unordered_map<std::string, RosterEntry>> parse(
      const std::string& text, const std::string& path, std::vector<std::string>* errors);

  bool empty() const;
  size_t size() const;
  // The entry of a token (compared in constant time per candidate length), or nullopt.
  std::optional<RosterEntry> find(const std::string& token) const;
  // The limit for a client name ("name:alice"), 0 when the roster sets none.
  int max_jobs_of(const std::string& client) const;

 private:
  mutable std::shared_mutex mu_;
  std::unordered_map<std::string, RosterEntry> by_token_;
  std::unordered_map<std::string, int> limit_by_name_;
};

// 128 random bits as 32 hex digits, from the system's random source.
std::string new_token();

}  // namespace rayfarm::server
