#include "roster.h"

#include "service.h"

#include <fstream>
#include <set>
#include <sstream>

namespace rayfarm::server {

std::optional<std::unordered_map<std::string, RosterEntry>> Roster::parse(
    const std::string& text, const std::string& path, std::vector<std::string>* errors) {
  std::unordered_map<std::string, RosterEntry> out;
  std::set<std::string> names;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  bool ok = true;
  auto fail = [&](const std::string& message) {
    ok = false;
    if (errors) errors->push_back(path + ":" + std::to_string(number) + ": " + message);
  };
  while (std::getline(in, line)) {
    ++number;
    if (const size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::string name, token, extra;
    if (!(words >> name)) continue;  // blank or comment
    if (!(words >> token)) {
      fail("'" + name + "' has no token: write NAME TOKEN");
      continue;
    }
    RosterEntry entry{name, 0};
    bool line_ok = true;
    while (words >> extra) {
      if (extra.rfind("max_jobs=", 0) == 0) {
        const std::string v = extra.substr(9);
        if (v.empty() || v.size() > 6 || v.find_first_not_of("0123456789") != std::string::npos ||
            std::stoi(v) < 1) {
          fail("max_jobs must be a whole number of at least 1, got '" + v + "'");
          line_ok = false;
        } else {
          entry.max_jobs = std::stoi(v);
        }
      } else {
        fail("unknown field '" + extra + "' (NAME TOKEN [max_jobs=N])");
        line_ok = false;
      }
    }
    if (token.size() < 16) {
      fail("the token of '" + name + "' is shorter than 16 characters: too easy to guess");
      line_ok = false;
    }
    if (!names.insert(name).second) {
      fail("'" + name + "' is listed twice");
      line_ok = false;
    }
    if (out.count(token)) {
      fail("the token of '" + name + "' is also someone else's");
      line_ok = false;
    }
    if (line_ok) out.emplace(token, entry);
  }
  if (!ok) return std::nullopt;
  return out;
}

bool Roster::load(const std::string& path, std::vector<std::string>* errors) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (errors) errors->push_back(path + ": cannot be read");
    return false;
  }
  std::ostringstream text;
  text << in.rdbuf();
  auto parsed = parse(text.str(), path, errors);
  if (!parsed) return false;
  std::unordered_map<std::string, int> limits;
  for (const auto& [token, entry] : *parsed)
    if (entry.max_jobs > 0) limits["name:" + entry.name] = entry.max_jobs;
  std::unique_lock lock(mu_);
  by_token_ = std::move(*parsed);
  limit_by_name_ = std::move(limits);
  return true;
}

bool Roster::empty() const {
  std::shared_lock lock(mu_);
  return by_token_.empty();
}

size_t Roster::size() const {
  std::shared_lock lock(mu_);
  return by_token_.size();
}

std::optional<RosterEntry> Roster::find(const std::string& token) const {
  std::shared_lock lock(mu_);
  // A hash lookup: its time depends on the token's hash, not on how much of a guess matched.
  auto it = by_token_.find(token);
  if (it == by_token_.end()) return std::nullopt;
  return it->second;
}

int Roster::max_jobs_of(const std::string& client) const {
  std::shared_lock lock(mu_);
  auto it = limit_by_name_.find(client);
  return it == limit_by_name_.end() ? 0 : it->second;
}

std::string new_token() { return random_id(); }

}  // namespace rayfarm::server
