// The service's own state: construction (and the expiry thread), cancelling, waiting, the
// counted slots of long requests, health, metrics and shutdown.
#include "service.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "file_blob_store.h"
#include "local_job_store.h"
#include "local_work_queue.h"

namespace rayfarm::server {

Backends make_local_backends(const std::filesystem::path& results_dir) {
  Backends b;
  b.blobs = std::make_unique<FileBlobStore>(results_dir);
  b.jobs = std::make_unique<LocalJobStore>(results_dir, *b.blobs);
  b.queue = std::make_unique<LocalWorkQueue>();
  return b;
}

Service::Service(Settings settings) : Service(settings, make_local_backends(settings.results_dir)) {}

Service::Service(Settings settings, Backends backends)
    : settings_(std::move(settings)),
      backends_(std::move(backends)),
      blobs_(*backends_.blobs),
      jobs_(backends_.jobs.get()),
      queue_(backends_.queue.get()),
      cache_(settings_.cache_bytes) {
  if (!settings_.tokens_file.empty()) {
    std::vector<std::string> errors;
    if (!roster_.load(settings_.tokens_file, &errors)) {
      std::string all;
      for (const std::string& e : errors) all += (all.empty() ? "" : "\n") + e;
      throw std::runtime_error(all);
    }
  }
  int workers = settings_.workers > 0 ? settings_.workers
                                      : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  Scheduler::Hooks hooks;
  hooks.started = [this](Job& job, const RenderStats& st) { return on_started(job, st); };
  hooks.progress = [this](Job& job, const RenderStats& st) { on_progress(job, st); };
  hooks.finished = [this](Job& job, RenderJob* render) { on_finished(job, render); };
  // At most 4 jobs of a client render at once (more would only split its share further).
  scheduler_ = std::make_unique<Scheduler>(*queue_, "local", workers, 4, settings_.job_timeout,
                                           std::move(hooks));
  if (!settings_.redis.empty())
    farm_ = std::make_unique<FarmBackend>(settings_, workers,
                                          [this](const std::string& id) { cancel_local(id); });
  load_samples();
  restore();
  janitor_ = std::thread([this] {
    // Every 10 s, or a quarter of the results' lifetime when that is shorter: a result is
    // gone within a quarter of --result-ttl past its time.
    const double every = settings_.expiry_every > 0 ? settings_.expiry_every
                                                    : std::min(10.0, settings_.result_ttl / 4);
    const long long ticks = std::max(1LL, static_cast<long long>(every * 10));  // of 100 ms
    while (!stop_janitor_) {
      for (long long i = 0; i < ticks && !stop_janitor_; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (!stop_janitor_) expire();
    }
  });
}

Service::~Service() {
  stop_janitor_ = true;
  if (janitor_.joinable()) janitor_.join();
  scheduler_->stop();
  if (farm_) farm_->stop();
}

void Service::cancel_local(const std::string& id) {
  if (auto job = jobs_->get(id); !job || is_final(job->state)) return;
  jobs_->request_cancel(id);
  scheduler_->cancel(id);
}

ApiError Service::cancel(const std::string& id, const std::string& client) {
  if (farm_) {
    // Every node hears of it on the cancel channel; this one's own render stops at once.
    ApiError e = farm_->cancel(id, client);
    if (!e) cancel_local(id);
    return e;
  }
  auto job = jobs_->get(id);
  if (!job) return api_error(404, "not_found", "no job " + id);
  if (job->client != client)
    return api_error(403, "forbidden", "only the client that submitted a job can cancel it");
  auto now = jobs_->request_cancel(id);
  if (now && is_final(now->state)) {
    if (now->state == JobState::canceled) return {};
    return api_error(409, "already_finished",
                     "the job has already " +
                         std::string(now->state == JobState::done ? "finished" : "failed"));
  }
  if (scheduler_->cancel(id)) return {};
  // Waiting for another job's render of its image: it leaves the waiting jobs and ends here.
  std::shared_ptr<Job> follower;
  {
    std::lock_guard lock(mu_);
    if (auto it = in_flight_.find(job->cache_key); it != in_flight_.end()) {
      auto& fs = it->second.followers;
      auto f = std::find_if(fs.begin(), fs.end(), [&](const auto& x) { return x->id == id; });
      if (f != fs.end()) {
        follower = *f;
        fs.erase(f);
      }
    }
  }
  if (follower) {
    follower->cancel_requested = true;
    on_finished(*follower, nullptr);
  }
  return {};
}

std::optional<Slot> Service::take_slot(Slot::Kind kind) {
  std::atomic<int>& count = kind == Slot::Kind::waiting ? waiters_ : streams_;
  const int cap =
      kind == Slot::Kind::waiting ? settings_.max_waiting_requests : settings_.max_event_streams;
  if (count.fetch_add(1) >= cap) {
    count.fetch_sub(1);
    return std::nullopt;
  }
  return Slot(&count);
}

std::optional<JobRecord> Service::await(const Slot&, const std::string& id,
                                        std::uint64_t since_version,
                                        std::chrono::steady_clock::time_point deadline) {
  if (farm_ && !jobs_->get(id)) {
    // Another node's job, or one spread over the farm: its record is polled (a unit takes
    // far longer than a step). A job rendered here is watched here, as without a farm.
    for (;;) {
      auto job = farm_->get(id);
      if (!job || job->version > since_version || is_final(job->state) || stopped() ||
          std::chrono::steady_clock::now() >= deadline || waiter_gone())
        return job;
      std::this_thread::sleep_until(
          std::min(deadline, std::chrono::steady_clock::now() + std::chrono::milliseconds(100)));
    }
  }
  // In short steps, so a shutdown is noticed without a wake-up from the store.
  for (;;) {
    auto step = std::min(deadline, std::chrono::steady_clock::now() + std::chrono::milliseconds(250));
    auto job = jobs_->watch(id, since_version, step);
    if (!job || job->version > since_version || is_final(job->state) || stopped() ||
        std::chrono::steady_clock::now() >= deadline || waiter_gone())
      return job;
  }
}

std::optional<JobRecord> Service::await_final(const Slot& slot, const std::string& id) {
  std::uint64_t seen = 0;
  for (;;) {
    auto job = await(slot, id, seen, std::chrono::steady_clock::time_point::max());
    if (!job || is_final(job->state) || stopped() || waiter_gone()) return job;
    seen = job->version;
  }
}

nlohmann::json Service::health() const {
  nlohmann::json h = {{"status", shutting_down_ ? "shutting_down" : "ok"},
                      {"queue_depth", queue_->depth()},
                      {"running", queue_->active()},
                      {"queue_capacity", settings_.queue_capacity},
                      {"workers", scheduler_->workers()}};
  if (farm_) {
    nlohmann::json redis;
    const bool reachable = farm_->healthy(redis);
    h["redis"] = redis;
    if (!reachable && !shutting_down_) h["status"] = "redis_unreachable";
  }
  return h;
}

std::string Service::metrics_text() const {
  Metrics::Gauges g;
  for (auto& [state, n] : jobs_->count_by_state()) g.jobs_by_state[std::string(to_string(state))] = n;
  g.queue_depth = static_cast<long>(queue_->depth());
  g.running = static_cast<long>(queue_->active());
  g.workers = scheduler_->workers();
  g.event_streams = streams_.load();
  g.waiting_requests = waiters_.load();
  g.waiting_loads = load_gate_.waiting();
  g.cache_bytes = static_cast<long>(cache_.bytes());
  return metrics_.render_text(g) + (farm_ ? farm_->metrics_text() : std::string());
}

void Service::shutdown() {
  if (shutting_down_.exchange(true)) return;
  scheduler_->drain(std::chrono::milliseconds(static_cast<long>(settings_.shutdown_grace * 1000)));
  scheduler_->stop();
  if (farm_) farm_->stop();  // its units go back to the farm at once
  stopped_ = true;  // waiting requests and event streams see it within their next step
}

}  // namespace rayfarm::server

namespace rayfarm::server {

bool Service::reload_roster() {
  if (settings_.tokens_file.empty()) return true;
  std::vector<std::string> errors;
  if (!roster_.load(settings_.tokens_file, &errors)) {
    for (const std::string& e : errors) std::fprintf(stderr, "rayfarmd: %s\n", e.c_str());
    std::fprintf(stderr, "rayfarmd: the roster is unchanged\n");
    return false;
  }
  std::fprintf(stderr, "rayfarmd: roster reread: %zu names\n", roster_.size());
  return true;
}

}  // namespace rayfarm::server
