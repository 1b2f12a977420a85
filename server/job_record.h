// A job's durable record: everything about a job that outlives the process that renders it
// (what was asked, by whom, where it stands), as a plain value with its one JSON form. The job
// stores keep it; the status document of GET /jobs/ID is built from it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "rayfarm/diagnostic.h"
#include "rayfarm/options.h"
#include "rayfarm/render.h"

namespace rayfarm::server {

enum class JobState { queued, running, done, failed, canceled };
std::string_view to_string(JobState s);
std::optional<JobState> job_state_from(std::string_view s);
inline bool is_final(JobState s) {
  return s == JobState::done || s == JobState::failed || s == JobState::canceled;
}

long long now_ms();  // wall clock, milliseconds since the epoch

struct JobRecord {
  // Fixed at submission.
  std::string id;      // 128 random bits, hex
  std::string client;  // roster name ("name:alice"), token digest or socket address
  RenderOptions options;  // with its queue class, options.priority
  std::string cache_key;  // content address of (scene, options); empty: not cacheable
  int width = 0;
  int height = 0;
  long long created_ms = 0;
  // What `rayfarm check` would warn about (a sphere behind the eye, a light inside a sphere):
  // a black image with no word of why is the worst answer a student can get.
  std::vector<Diagnostic> warnings;
  // Idempotency-Key of the POST /render that made it, and the digest of that request (scene,
  // textures, options): the same key with another request is refused.
  std::string idempotency_key;
  std::string request_digest;

  // Changed only through JobStore::transition, request_cancel and update_progress.
  JobState state = JobState::queued;
  long long started_ms = 0;
  long long finished_ms = 0;
  std::string error;
  std::string error_code;
  int attempts = 0;  // renders started (a crash loop is failed after a few)
  bool cache_hit = false;
  bool cancel_requested = false;  // by its client (a shutdown is not a cancel)
  std::string image_name;         // where the result is kept (the cache key, or the id)
  // SHA-256 of each texture file the scene names, kept while the job may still render.
  std::vector<std::string> textures;
  RenderStats stats;          // last known
  std::uint64_t version = 0;  // bumped by the store on every change (watch, event streams)
  std::uint64_t sequence = 0; // submission order, given by the store (not part of the JSON)
};

// The record's one JSON form (the results directory's jobs/ID.json; a Redis hash later).
// from_json reads records older builds wrote, and fails (nullopt) only without a valid id.
nlohmann::json to_json(const JobRecord& r);
// A record's warnings as stored (to_json's "warnings"), and back.
nlohmann::json warnings_json(const std::vector<Diagnostic>& warnings);
std::vector<Diagnostic> warnings_from_json(const nlohmann::json& j);
std::optional<JobRecord> record_from_json(const nlohmann::json& j);

// JSON text that never throws: user input that is not UTF-8 (a camera name in a query, a
// byte in a scene quoted by an error message) comes out as U+FFFD.
std::string json_text(const nlohmann::json& j);

// The status of GET /jobs/ID (docs/http-api.md#get-jobsid). `queue_position` from the queue.
nlohmann::json job_status(const JobRecord& job, int queue_position);

}  // namespace rayfarm::server
