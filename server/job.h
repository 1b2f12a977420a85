// A render job as the server tracks it: what was asked, by whom, and where it stands.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rayfarm/diagnostic.h"
#include "rayfarm/options.h"
#include "rayfarm/render.h"
#include "rayfarm/scene.h"

namespace rayfarm::server {

enum class JobState { queued, running, done, failed, canceled };
std::string_view to_string(JobState s);
std::optional<JobState> job_state_from(std::string_view s);
inline bool is_final(JobState s) {
  return s == JobState::done || s == JobState::failed || s == JobState::canceled;
}

long long now_ms();  // wall clock, milliseconds since the epoch

struct Job {
  // Fixed at submission.
  std::string id;          // 128 random bits, hex
  std::string client;      // token digest or socket address
  std::shared_ptr<const Scene> scene;
  RenderOptions options;
  std::string cache_key;   // content address of (scene, options); empty: not cacheable
  int width = 0;
  int height = 0;
  long long created_ms = 0;
  // What `rayfarm check` would warn about (a sphere behind the eye, a light inside a sphere):
  // a black image with no word of why is the worst answer a student can get.
  std::vector<Diagnostic> warnings;

  // Everything below is guarded by mu; `changed` is notified on every update.
  mutable std::mutex mu;
  std::condition_variable changed;
  JobState state = JobState::queued;
  long long started_ms = 0;
  long long finished_ms = 0;
  std::string error;
  std::string error_code;
  int attempts = 0;  // renders started (a crash loop is failed after a few)
  bool cache_hit = false;
  std::string image_name;  // where the result is kept (the cache key, or the id)
  // SHA-256 of each of scene->textures' files: kept in the results directory, and named by
  // the record, until the job is final. Empty for a cache hit.
  std::vector<std::string> textures;
  RenderStats stats;                       // last known
  std::uint64_t version = 0;               // bumped on every change (event streams)
  std::chrono::steady_clock::time_point run_start{};

  // Set by the scheduler while rendering.
  std::shared_ptr<RenderJob> render;
  std::atomic<bool> cancel_requested{false};  // by its client (not by a shutdown)
  std::atomic<bool> timed_out{false};
  std::uint64_t sequence = 0;  // submission order, for queue positions
};

// JSON text that never throws: user input that is not UTF-8 (a camera name in a query, a
// byte in a scene quoted by an error message) comes out as U+FFFD.
std::string json_text(const nlohmann::json& j);

// The status of GET /jobs/ID (docs/http-api.md#get-jobsid). `queue_position` from the scheduler.
nlohmann::json job_status(const Job& job, int queue_position);

}  // namespace rayfarm::server
