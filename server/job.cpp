// Job states and the status document.
#include "job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>

#include "api_error.h"

namespace rayfarm::server {

std::string_view to_string(JobState s) {
  switch (s) {
    case JobState::queued: return "queued";
    case JobState::running: return "running";
    case JobState::done: return "done";
    case JobState::failed: return "failed";
    case JobState::canceled: return "canceled";
  }
  return "queued";
}

std::optional<JobState> job_state_from(std::string_view s) {
  for (JobState st : {JobState::queued, JobState::running, JobState::done, JobState::failed,
                      JobState::canceled})
    if (to_string(st) == s) return st;
  return std::nullopt;
}

long long now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

namespace {

nlohmann::json iso_or_null(long long ms) {
  if (ms <= 0) return nullptr;
  std::time_t secs = static_cast<std::time_t>(ms / 1000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char buf[40];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  char out[48];
  std::snprintf(out, sizeof out, "%s.%03lldZ", buf, ms % 1000);
  return std::string(out);
}

// How much of the image was rendered. A canceled or failed render is "finished" too, but
// only a done job is complete.
double rendered_fraction(const Job& job) {
  if (job.state == JobState::done) return 1.0;
  const RenderStats& st = job.stats;
  if (st.tiles_per_pass == 0 || st.spp_target == 0) return 0.0;
  double f = (st.spp_done + static_cast<double>(st.tiles_done) / st.tiles_per_pass) / st.spp_target;
  return std::min(f, 1.0);
}

}  // namespace

std::string json_text(const nlohmann::json& j) {
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

namespace {

// An option's text as the JSON value it is: 16 and 0.5 numbers, true and false booleans, a
// colour "0.1,0.2,0.3" an array; words ("unlimited", "cpsc102") stay strings.
nlohmann::json typed_value(const std::string& v) {
  if (v == "true") return true;
  if (v == "false") return false;
  if (!v.empty() && v.find_first_not_of("0123456789") == std::string::npos && v.size() <= 19)
    return std::stoull(v);
  if (v.find(',') != std::string::npos) {
    nlohmann::json parts = nlohmann::json::array();
    size_t start = 0;
    while (start <= v.size()) {
      size_t end = v.find(',', start);
      if (end == std::string::npos) end = v.size();
      nlohmann::json part = typed_value(v.substr(start, end - start));
      if (!part.is_number()) return v;
      parts.push_back(part);
      start = end + 1;
    }
    return parts;
  }
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (!v.empty() && end && *end == '\0' && std::isfinite(d)) return d;
  return v;
}

}  // namespace

nlohmann::json job_status(const Job& job, int queue_position) {
  std::lock_guard lock(job.mu);
  const RenderStats& st = job.stats;
  nlohmann::json j;
  j["id"] = job.id;
  j["state"] = to_string(job.state);
  const double progress = rendered_fraction(job);
  j["progress"] = progress;
  j["queue_position"] = queue_position;
  j["created_at"] = iso_or_null(job.created_ms);
  j["started_at"] = iso_or_null(job.started_ms);
  j["finished_at"] = iso_or_null(job.finished_ms);
  long long end = job.finished_ms > 0 ? job.finished_ms : now_ms();
  j["elapsed_ms"] = job.started_ms > 0 ? end - job.started_ms : 0;
  if (job.state == JobState::running && progress > 0.01 && st.render_ms > 0)
    j["eta_ms"] = std::llround(st.render_ms * (1 - progress) / progress);
  else
    j["eta_ms"] = is_final(job.state) ? nlohmann::json(0) : nlohmann::json(nullptr);
  j["spp_done"] = st.spp_done;
  j["error_estimate"] = st.error_estimate >= 0 ? nlohmann::json(st.error_estimate)
                                               : nlohmann::json(nullptr);
  double secs = st.render_ms / 1000;
  j["stats"] = {{"rays", {{"primary", st.primary_rays},
                          {"shadow", st.shadow_rays},
                          {"reflection", st.reflection_rays}}},
                {"rays_per_second", secs > 0 ? st.total_rays() / secs : 0.0},
                {"render_ms", st.render_ms},
                {"prepare_ms", st.prepare_ms},
                {"parts", st.parts},
                {"stop_reason", st.stop_reason},
                {"cache", job.cache_hit ? "hit" : "miss"}};
  nlohmann::json opts = nlohmann::json::object();
  for (auto& [k, v] : option_pairs(job.options)) opts[k] = typed_value(v);
  opts["width"] = job.width;
  opts["height"] = job.height;
  j["options"] = opts;
  // Who it belongs to, by roster name (an address or a token's digest is nobody's business).
  if (job.client.rfind("name:", 0) == 0) j["owner"] = job.client.substr(5);
  nlohmann::json warnings = nlohmann::json::array();
  for (const Diagnostic& d : job.warnings) warnings.push_back(diagnostic_json(d));
  j["warnings"] = std::move(warnings);
  j["error"] = job.error.empty() ? nlohmann::json(nullptr)
                                 : nlohmann::json{{"code", job.error_code}, {"message", job.error}};
  j["links"] = {{"self", "/jobs/" + job.id},
                {"image", "/jobs/" + job.id + "/image"},
                {"events", "/jobs/" + job.id + "/events"}};
  return j;
}

}  // namespace rayfarm::server
