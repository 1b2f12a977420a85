// The render service without HTTP: accepting jobs (checked, limited, durable), the job
// table, results and their cache, expiry, samples, health and metrics. The HTTP layer
// (http_api.cpp, routes_*.cpp) only translates requests to these calls. Its parts:
// submission.cpp, results.cpp, samples.cpp, recovery.cpp (restart), expiry.cpp.
#pragma once

#include <atomic>
#include <filesystem>
#include <map>
#include <unordered_map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "api_error.h"
#include "image_cache.h"
#include "job.h"
#include "metrics.h"
#include "roster.h"
#include "scheduler.h"
#include "settings.h"
#include "store.h"
#include "textures.h"

namespace rayfarm::server {

using Params = std::vector<std::pair<std::string, std::string>>;

struct Submitted {
  std::shared_ptr<Job> job;
  ApiError error;
};

struct Sample {
  std::string name;
  std::string description;
  std::filesystem::path path;
  TextureFiles textures;  // the bundle's files beside it, read at start (requests name none)
};

class Service {
 public:
  explicit Service(Settings settings);
  ~Service();

  const Settings& settings() const { return settings_; }
  const Roster& roster() const { return roster_; }
  // Rereads --tokens-file; on errors (printed) the roster stays as it was.
  bool reload_roster();

  // Checks the scene and options against the format and the limits, answers from the cache
  // when it can, and otherwise queues the job; the job is on disk before this returns.
  // `textures`: the files the scene names, by the path it writes (docs/http-api.md#textures).
  Submitted submit(const std::string& scene_text, const Params& options, const std::string& client,
                   const TextureFiles& textures = {});

  std::shared_ptr<Job> find(const std::string& id) const;
  std::vector<std::shared_ptr<Job>> jobs_of(const std::string& client, size_t limit) const;
  ApiError cancel(const std::string& id, const std::string& client);
  int queue_position(const Job& job) const { return scheduler_->queue_position(job); }
  nlohmann::json status(const Job& job) const { return job_status(job, queue_position(job)); }

  // The result PNG of a done job; null when it has expired.
  std::shared_ptr<const std::string> result_png(const Job& job);
  // The image so far (or the result when done).
  std::optional<Image> current_image(const Job& job);

  const std::vector<Sample>& samples() const { return samples_; }
  const Sample* sample(const std::string& name) const;

  nlohmann::json health() const;
  std::string metrics_text() const;
  Metrics& metrics() { return metrics_; }

  // Counted slots for requests that hold a connection open.
  bool acquire_stream();
  void release_stream();
  bool acquire_waiter();
  void release_waiter();

  bool shutting_down() const { return shutting_down_.load(); }
  // Rendering has stopped (after the shutdown grace period): waiting requests give up.
  bool stopped() const { return stopped_.load(); }
  // Stops accepting work, lets running renders finish for the grace period, then persists
  // what is left (it runs again after a restart).
  void shutdown();

  // Removes finished jobs older than the TTL and images over the size budget.
  void expire();

 private:
  ApiError check_limits(const Scene& scene, const RenderOptions& options, int width, int height);
  // textures.cpp
  ApiError check_uploads(const TextureFiles& files) const;
  ApiError resolve_uploads(Scene& scene, const TextureFiles& files) const;
  void keep_textures(const Job& job, const Scene& scene, const TextureFiles& files);
  void release_textures(Job& job);
  std::shared_ptr<const Scene> reload_scene(const std::string& text,
                                            const std::vector<std::string>& hashes);
  void sweep_textures();
  void restore();
  void on_finished(Job& job, RenderJob* render);
  void persist(const Job& job);
  std::shared_ptr<Job> new_job(const std::string& client);
  void load_samples();

  Settings settings_;
  Roster roster_;
  ResultStore store_;
  ImageCache cache_;
  Metrics metrics_;
  std::unique_ptr<Scheduler> scheduler_;

  mutable std::mutex mu_;
  std::map<std::string, std::shared_ptr<Job>> jobs_;
  // How many kept (or being submitted) jobs name each image: expiry deletes an image only when
  // none does, without scanning the table under its lock.
  std::unordered_map<std::string, int> image_refs_;
  // How many unfinished jobs need each texture file in the results directory (by its hash).
  std::unordered_map<std::string, int> texture_refs_;
  std::uint64_t sequence_ = 0;

  std::vector<Sample> samples_;
  std::atomic<int> streams_{0};
  std::atomic<int> waiters_{0};
  std::atomic<bool> shutting_down_{false};
  std::atomic<bool> stopped_{false};
  std::atomic<bool> stop_janitor_{false};
  std::thread janitor_;
};

std::string random_id();  // 128 random bits as 32 hex digits

}  // namespace rayfarm::server
