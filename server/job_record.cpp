// The job record's JSON form, its states and priorities, and the status document.
#include "job_record.h"

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

nlohmann::json warnings_json(const std::vector<Diagnostic>& warnings) {
  nlohmann::json out = nlohmann::json::array();
  for (const Diagnostic& d : warnings)
    out.push_back({{"code", d.code},
                   {"message", d.message},
                   {"line", d.where.line},
                   {"column", d.where.column},
                   {"path", d.where.path}});
  return out;
}

std::vector<Diagnostic> warnings_from_json(const nlohmann::json& j) {
  std::vector<Diagnostic> out;
  if (!j.is_array()) return out;
  for (auto& w : j)
    if (w.is_object())
      out.push_back({Severity::warning, w.value("code", ""), w.value("message", ""),
                     {w.value("line", 0), w.value("column", 0), w.value("path", "")}});
  return out;
}

nlohmann::json to_json(const JobRecord& r) {
  nlohmann::json options = nlohmann::json::object();
  for (auto& [k, v] : option_pairs(r.options)) options[k] = v;
  nlohmann::json warnings = warnings_json(r.warnings);
  nlohmann::json record = {{"id", r.id},
                           {"client", r.client},
                           {"state", to_string(r.state)},
                           {"options", options},
                           {"cache_key", r.cache_key},
                           {"image_name", r.image_name},
                           {"created_ms", r.created_ms},
                           {"started_ms", r.started_ms},
                           {"finished_ms", r.finished_ms},
                           {"attempts", r.attempts},
                           {"error", r.error},
                           {"error_code", r.error_code},
                           {"cache_hit", r.cache_hit},
                           {"cancel_requested", r.cancel_requested},
                           {"width", r.width},
                           {"height", r.height},
                           {"version", r.version},
                           {"warnings", warnings},
                           {"stats",
                            {{"primary", r.stats.primary_rays},
                             {"shadow", r.stats.shadow_rays},
                             {"reflection", r.stats.reflection_rays},
                             {"prepare_ms", r.stats.prepare_ms},
                             {"render_ms", r.stats.render_ms},
                             {"spp_done", r.stats.spp_done},
                             {"spp_target", r.stats.spp_target},
                             {"tiles_done", r.stats.tiles_done},
                             {"tiles_per_pass", r.stats.tiles_per_pass},
                             {"error_estimate", r.stats.error_estimate},
                             {"stop_reason", r.stats.stop_reason},
                             {"finished", r.stats.finished},
                             {"parts", r.stats.parts}}}};
  if (!r.idempotency_key.empty()) {
    record["idempotency_key"] = r.idempotency_key;
    record["request_digest"] = r.request_digest;
  }
  // Only a job that may still render needs its textures; the files go when it ends.
  if (!is_final(r.state) && !r.textures.empty()) record["textures"] = r.textures;
  return record;
}

namespace {

std::vector<std::string> strings_of(const nlohmann::json& j, const char* key) {
  std::vector<std::string> out;
  if (j.contains(key) && j[key].is_array())
    for (auto& v : j[key])
      if (v.is_string()) out.push_back(v.get<std::string>());
  return out;
}

}  // namespace

std::optional<JobRecord> record_from_json(const nlohmann::json& j) {
  if (!j.is_object()) return std::nullopt;
  try {
    JobRecord r;
    r.id = j.value("id", "");
    if (r.id.size() != 32) return std::nullopt;
    r.client = j.value("client", "");
    r.state = job_state_from(j.value("state", "")).value_or(JobState::failed);
    // Every option prints as text it reads back; the profile's defaults come back explicit.
    if (j.contains("options") && j["options"].is_object())
      for (auto& [k, v] : j["options"].items())
        if (v.is_string()) apply_option(r.options, k, v.get<std::string>());
    r.cache_key = j.value("cache_key", "");
    r.image_name = j.value("image_name", r.id);
    r.created_ms = j.value("created_ms", 0LL);
    r.started_ms = j.value("started_ms", 0LL);
    r.finished_ms = j.value("finished_ms", 0LL);
    r.attempts = j.value("attempts", 0);
    r.error = j.value("error", "");
    r.error_code = j.value("error_code", "");
    r.cache_hit = j.value("cache_hit", false);
    r.cancel_requested = j.value("cancel_requested", false);
    r.width = j.value("width", 0);
    r.height = j.value("height", 0);
    r.version = j.value("version", 0ULL);
    r.idempotency_key = j.value("idempotency_key", "");
    r.request_digest = j.value("request_digest", "");
    r.textures = strings_of(j, "textures");
    if (j.contains("warnings")) r.warnings = warnings_from_json(j["warnings"]);
    if (j.contains("stats") && j["stats"].is_object()) {
      const auto& st = j["stats"];
      r.stats.primary_rays = st.value("primary", 0ULL);
      r.stats.shadow_rays = st.value("shadow", 0ULL);
      r.stats.reflection_rays = st.value("reflection", 0ULL);
      r.stats.prepare_ms = st.value("prepare_ms", 0.0);
      r.stats.render_ms = st.value("render_ms", 0.0);
      r.stats.spp_done = st.value("spp_done", 0);
      r.stats.spp_target = st.value("spp_target", 1);
      r.stats.tiles_done = st.value("tiles_done", 0);
      r.stats.tiles_per_pass = st.value("tiles_per_pass", 0);
      r.stats.error_estimate = st.value("error_estimate", -1.0);
      r.stats.stop_reason = st.value("stop_reason", "");
      r.stats.finished = st.value("finished", false);
      r.stats.parts = strings_of(st, "parts");
    }
    // Records of older builds kept neither: a done job is complete.
    if (r.state == JobState::done && !(j.contains("stats") && j["stats"].is_object() &&
                                       j["stats"].contains("spp_target"))) {
      r.stats.finished = true;
      r.stats.spp_target = r.stats.spp_done;
    }
    return r;
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;  // a field of the wrong type: a foreign or damaged file
  }
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
double rendered_fraction(const JobRecord& job) {
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

nlohmann::json job_status(const JobRecord& job, int queue_position) {
  const RenderStats& st = job.stats;
  nlohmann::json j;
  j["id"] = job.id;
  j["state"] = to_string(job.state);
  j["priority"] = to_string(job.options.priority);
  const double progress = rendered_fraction(job);
  j["progress"] = progress;
  // From 1 while queued, 0 after: a worker may take the job between the record's reading
  // and the queue's, and "queued, position 0" would be neither.
  j["queue_position"] = job.state == JobState::queued ? std::max(queue_position, 1) : 0;
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
