// rayfarmd as a node of a farm (--redis): where Service goes instead of its local job store,
// queue and results when the jobs live in Redis. Why not JobStore/WorkQueue/BlobStore over
// Redis: the farm's unit of work is a range of tiles, taken by any node's FarmNode threads,
// and a job's course (queued, running, assembling, ended) is changed only by the rayfarm1
// Functions; the local interfaces hand whole jobs to this process's Scheduler and let it
// transition records itself. So Service keeps one branch per concern (submit, read, list,
// cancel, wait, image, health, metrics) and this class is the whole farm side of each.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "api_error.h"
#include "job_record.h"
#include "settings.h"

namespace rayfarm::server {

// Redis could not answer (down, reconnecting, out of memory): the HTTP layer answers 503 with
// Retry-After (http_api.cpp).
struct Unavailable : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class FarmBackend {
 public:
  // Throws std::runtime_error on a bad URL or password file (the process does not start).
  // `on_cancel` runs for every job canceled anywhere in the farm (this node's own jobs stop).
  FarmBackend(const Settings& settings, int workers,
              std::function<void(const std::string&)> on_cancel = {});
  ~FarmBackend();

  // Submits a checked job (its id, client, options, size and cache key set): answered from
  // the farm's results when its image is kept (recorded done), else queued for the farm.
  // Errors: 429 (client limit), 503 (full, Redis unavailable or out of memory).
  // `local`: the job is rendered here alone (small, or with texture files only this node
  // has); when `Outcome::local` comes back the caller queues it on its own scheduler and ends
  // it with finish_local().
  struct Outcome {
    std::optional<JobRecord> job;
    ApiError error;
    bool replayed = false;
    bool local = false;
  };
  Outcome submit(JobRecord job, const std::string& scene_text, int max_jobs_of_client,
                 bool local);
  // Ends a local job in the farm: its image stored under its result key first, then the record
  // (so a node that reads "done" finds the image). Tried `attempts` times, briefly apart;
  // false when Redis did not take it (the farm's job limit then ends the record).
  bool finish_local(const JobRecord& job, JobState state, const std::string& code,
                    const std::string& error, const std::string* png, const RenderStats& stats,
                    int attempts = 5);

  // How far this node's render of a local job has got (0-1): the other nodes see it after
  // the next heartbeat. Never blocks on Redis.
  void local_progress(const std::string& id, double fraction);

  // Throw Unavailable when Redis does not answer.
  std::optional<JobRecord> get(const std::string& id);
  std::vector<JobRecord> list(const std::string& client, size_t limit);
  ApiError cancel(const std::string& id, const std::string& client);
  int queue_position(const std::string& id);
  std::shared_ptr<const std::string> png(const std::string& result_key);

  // Reachable or not, and the details for /healthz; never throws.
  bool healthy(nlohmann::json& details);
  // Prometheus lines of this node (units, reclaims, Redis round trips, node id).
  std::string metrics_text() const;
  const std::string& node() const;
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rayfarm::server
