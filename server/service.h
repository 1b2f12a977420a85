// The render service without HTTP: accepting jobs (checked, limited, durable), waiting for
// them, results and their cache, expiry, samples, health and metrics, over a JobStore, a
// WorkQueue and a BlobStore. The HTTP layer (http_api.cpp, routes_*.cpp) only translates
// requests to these calls and sees jobs as JobRecords. Its parts: submission.cpp,
// results.cpp, samples.cpp, recovery.cpp (restart), expiry.cpp.
#pragma once

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <map>
#include <unordered_map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "api_error.h"
#include "blob_store.h"
#include "farm_backend.h"
#include "image_cache.h"
#include "job.h"
#include "job_store.h"
#include "load_gate.h"
#include "metrics.h"
#include "roster.h"
#include "scheduler.h"
#include "settings.h"
#include "textures.h"
#include "work_queue.h"

namespace rayfarm::server {

using Params = std::vector<std::pair<std::string, std::string>>;

// How a job is asked for, beyond its scene and options.
struct SubmitHow {
  // The queue class when neither the request's options nor the scene's render block name one
  // (interactive for a client that waits for the answer).
  Priority default_priority = Priority::normal;
  // Idempotency-Key (checked by the route; empty: none): the same key from the same client
  // gives the job it already made (`replayed`), and another request with it is refused.
  std::string idempotency_key;
};

struct Submitted {
  std::optional<JobRecord> job;
  ApiError error;
  bool replayed = false;  // the job an earlier request with the same Idempotency-Key made
};

// The backends a Service runs on; make_local_backends() gives today's single process.
struct Backends {
  std::unique_ptr<BlobStore> blobs;
  std::unique_ptr<JobStore> jobs;
  std::unique_ptr<WorkQueue> queue;
};
// Files in `results_dir` (memory only when it is empty), the queue in this process.
Backends make_local_backends(const std::filesystem::path& results_dir);

class Service;

// A counted place for a request that holds its connection open while it waits: a waiting
// request (?wait=1, /compare and /grade with a scene) or an event stream. Released when it is
// destroyed.
class Slot {
 public:
  enum class Kind { waiting, stream };
  Slot(Slot&& other) noexcept : counter_(std::exchange(other.counter_, nullptr)) {}
  Slot& operator=(Slot&&) = delete;
  ~Slot() {
    if (counter_) counter_->fetch_sub(1);
  }

 private:
  friend class Service;
  explicit Slot(std::atomic<int>* counter) : counter_(counter) {}
  std::atomic<int>* counter_;
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
  Service(Settings settings, Backends backends);
  ~Service();

  const Settings& settings() const { return settings_; }
  // Held while a scene text of this size is read (load_gate.h): every request that reads a
  // scene takes one before load_scene.
  LoadGate::Pass enter_load(size_t bytes) { return load_gate_.enter(bytes); }
  const Roster& roster() const { return roster_; }
  // Rereads --tokens-file; on errors (printed) the roster stays as it was.
  bool reload_roster();

  // Checks the scene and options against the format and the limits, answers from the cache
  // when it can, and otherwise queues the job; the job is on disk before this returns.
  // `textures`: the files the scene names, by the path it writes (docs/http-api.md#textures).
  Submitted submit(const std::string& scene_text, const Params& options, const std::string& client,
                   const TextureFiles& textures = {}, const SubmitHow& how = {});

  // In a farm (--redis) these read Redis, and throw Unavailable when it does not answer.
  // A farm's job rendered on this node is read here: its record has the progress and warnings.
  std::optional<JobRecord> find(const std::string& id) const {
    if (auto local = jobs_->get(id); local || !farm_) return local;
    return farm_->get(id);
  }
  std::vector<JobRecord> jobs_of(const std::string& client, size_t limit) const {
    return farm_ ? farm_->list(client, limit) : jobs_->list_by_client(client, limit);
  }
  ApiError cancel(const std::string& id, const std::string& client);
  int queue_position(const std::string& id) const {
    return farm_ && !jobs_->get(id) ? farm_->queue_position(id) : queue_->position(id);
  }
  // This process's farm node; null without --redis.
  FarmBackend* farm() const { return farm_.get(); }
  nlohmann::json status(const JobRecord& job) const {
    // A job waiting for another's render of its image is where that one is.
    const auto leader = job.state == JobState::queued ? leader_of(job.id, job.cache_key)
                                                      : std::nullopt;
    return job_status(job, queue_position(leader ? *leader : job.id));
  }

  // A counted slot of `kind`; nullopt when all are taken.
  std::optional<Slot> take_slot(Slot::Kind kind);
  // The one way a request waits for a job, holding a slot: returns the record once its
  // version is above `since_version` (or it is final), at the deadline, or when rendering has
  // stopped (shutdown), whichever comes first; nullopt when the job is unknown.
  std::optional<JobRecord> await(const Slot& slot, const std::string& id,
                                 std::uint64_t since_version,
                                 std::chrono::steady_clock::time_point deadline);
  // await() until the job is final or rendering stops.
  std::optional<JobRecord> await_final(const Slot& slot, const std::string& id);
  // Whether the client of the request waiting on this thread has gone (the HTTP layer's
  // answer): await() then returns at its next step, the job as it is, and frees its slot for
  // a request someone still waits for. The job itself goes on.
  void set_waiter_gone(bool (*gone)()) { waiter_gone_ = gone; }

  // The result PNG of a done job; null when it has expired.
  std::shared_ptr<const std::string> result_png(const JobRecord& job);
  // The image so far (or the result when done).
  std::optional<Image> current_image(const JobRecord& job);

  const std::vector<Sample>& samples() const { return samples_; }
  const Sample* sample(const std::string& name) const;

  nlohmann::json health() const;
  std::string metrics_text() const;
  Metrics& metrics() { return metrics_; }

  bool shutting_down() const { return shutting_down_.load(); }
  // Rendering has stopped (after the shutdown grace period): waiting requests give up.
  bool stopped() const { return stopped_.load(); }
  // Stops accepting work, lets running renders finish for the grace period, then persists
  // what is left (it runs again after a restart).
  void shutdown();

  // Removes finished jobs older than the TTL and images over the size budget.
  void expire();

 private:
  Submitted submit_new(const std::string& scene_text, const Params& options,
                       const std::string& client, const TextureFiles& textures,
                       const SubmitHow& how, const std::string& digest);
  ApiError check_limits(const Scene& scene, const RenderOptions& options, int width, int height);
  // textures.cpp
  ApiError check_uploads(const TextureFiles& files) const;
  ApiError resolve_uploads(Scene& scene, const TextureFiles& files) const;
  void keep_textures(const std::vector<std::string>& hashes, const Scene& scene,
                     const TextureFiles& files);
  void release_textures(const std::vector<std::string>& hashes);
  std::shared_ptr<const Scene> reload_scene(const std::string& text,
                                            const std::vector<std::string>& hashes);
  void sweep_textures();
  void restore();
  bool on_started(Job& job, const RenderStats& stats);
  void on_progress(Job& job, const RenderStats& stats);
  void on_finished(Job& job, RenderJob* render);
  // Schedules a job, or (outside a farm, with a content key) has it wait for the render of
  // the same image under way, or ends it with that image when it was rendered meanwhile.
  enum class Scheduled { queued, waits, answered };
  Scheduled schedule(std::shared_ptr<Job> run, const std::string& cache_key);
  // Marks a job that waits for `leader`'s render running with it, unless it was handed on
  // since `handovers` was read.
  void mirror_running(Job& follower, int handovers, const JobRecord& leader);
  // The jobs waiting for `leader`'s render, taken off (none when it has none).
  std::vector<std::shared_ptr<Job>> take_followers(const Job& leader);
  // How many jobs wait for another's render: of `client`, or of all with null.
  std::size_t followers_of(const std::string* client) const;
  // The rendering job a waiting job follows, if it is one.
  std::optional<std::string> leader_of(const std::string& id, const std::string& cache_key) const;
  // Ends a job that waited for `leader`'s render: in its final state, or queued again to
  // render itself (`requeue`).
  void end_followers(std::vector<std::shared_ptr<Job>> followers, const JobRecord& leader,
                     bool requeue);
  // Stops this node's render of a job (in a farm: a cancel heard from any node).
  void cancel_local(const std::string& id);
  void load_samples();
  void release_image(const std::string& name);

  Settings settings_;
  Roster roster_;
  Backends backends_;
  BlobStore& blobs_;
  JobStore* jobs_;
  WorkQueue* queue_;
  ImageCache cache_;
  Metrics metrics_;
  std::unique_ptr<Scheduler> scheduler_;
  std::unique_ptr<FarmBackend> farm_;  // --redis: jobs, queue and results in the farm

  mutable std::mutex mu_;
  // How many kept (or being submitted) jobs name each image: expiry deletes an image only when
  // none does, without scanning the table.
  std::unordered_map<std::string, int> image_refs_;
  // How many unfinished jobs need each texture file in the results directory (by its hash).
  std::unordered_map<std::string, int> texture_refs_;
  // (client, Idempotency-Key) of submissions under way: a second one at once is a 409.
  std::set<std::pair<std::string, std::string>> keys_in_flight_;
  // Renders under way by their image's content key, with the jobs of the same image that
  // wait for them instead of rendering it again (a class submitting one scene, a grader's
  // references): they share the render's state and progress, and end with it.
  struct InFlight {
    std::string leader;                          // the job rendering it
    Priority priority = Priority::normal;        // its queue class
    std::vector<std::shared_ptr<Job>> followers;  // in the order they came
  };
  std::unordered_map<std::string, InFlight> in_flight_;

  std::vector<Sample> samples_;
  std::atomic<int> streams_{0};
  std::atomic<int> waiters_{0};
  bool (*waiter_gone_)() = nullptr;
  bool waiter_gone() const { return waiter_gone_ && waiter_gone_(); }
  LoadGate load_gate_{static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))};
  std::atomic<bool> shutting_down_{false};
  std::atomic<bool> stopped_{false};
  std::atomic<bool> stop_janitor_{false};
  std::thread janitor_;
};

std::string random_id();  // 128 random bits as 32 hex digits

}  // namespace rayfarm::server
