// The service's own state: construction (and the expiry thread), the job table, cancelling,
// the counted slots of long requests, health, metrics and shutdown.
#include "service.h"

#include <cstdio>
#include <stdexcept>

#include <algorithm>

namespace rayfarm::server {

Service::Service(Settings settings)
    : settings_(std::move(settings)),
      store_(settings_.results_dir),
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
  hooks.started = [this](Job& job) { persist(job); };
  hooks.finished = [this](Job& job, RenderJob* render) { on_finished(job, render); };
  scheduler_ = std::make_unique<Scheduler>(workers, 4, settings_.job_timeout, std::move(hooks));
  load_samples();
  restore();
  janitor_ = std::thread([this] {
    while (!stop_janitor_) {
      for (int i = 0; i < 100 && !stop_janitor_; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (!stop_janitor_) expire();
    }
  });
}

Service::~Service() {
  stop_janitor_ = true;
  if (janitor_.joinable()) janitor_.join();
  scheduler_->stop();
}

std::shared_ptr<Job> Service::find(const std::string& id) const {
  std::lock_guard lock(mu_);
  auto it = jobs_.find(id);
  return it == jobs_.end() ? nullptr : it->second;
}

std::vector<std::shared_ptr<Job>> Service::jobs_of(const std::string& client, size_t limit) const {
  std::vector<std::shared_ptr<Job>> out;
  {
    std::lock_guard lock(mu_);
    for (auto& [id, j] : jobs_)
      if (j->client == client) out.push_back(j);
  }
  std::sort(out.begin(), out.end(), [](auto& a, auto& b) { return a->sequence > b->sequence; });
  if (out.size() > limit) out.resize(limit);
  return out;
}

ApiError Service::cancel(const std::string& id, const std::string& client) {
  auto job = find(id);
  if (!job) return api_error(404, "not_found", "no job " + id);
  if (job->client != client)
    return api_error(403, "forbidden", "only the client that submitted a job can cancel it");
  {
    std::lock_guard jl(job->mu);
    if (is_final(job->state)) {
      if (job->state == JobState::canceled) return {};
      return api_error(409, "already_finished",
                       "the job has already " +
                           std::string(job->state == JobState::done ? "finished" : "failed"));
    }
  }
  scheduler_->cancel(job);
  return {};
}

void Service::persist(const Job& job) {
  try {
    store_.save_record(job);
  } catch (const std::exception&) {
    // The job goes on; after a restart it runs again, which is safe.
  }
}

bool Service::acquire_stream() {
  if (streams_.fetch_add(1) >= settings_.max_event_streams) {
    streams_.fetch_sub(1);
    return false;
  }
  return true;
}
void Service::release_stream() { streams_.fetch_sub(1); }
bool Service::acquire_waiter() {
  if (waiters_.fetch_add(1) >= settings_.max_waiting_requests) {
    waiters_.fetch_sub(1);
    return false;
  }
  return true;
}
void Service::release_waiter() { waiters_.fetch_sub(1); }

nlohmann::json Service::health() const {
  return {{"status", shutting_down_ ? "shutting_down" : "ok"},
          {"queue_depth", scheduler_->waiting()},
          {"running", scheduler_->active()},
          {"queue_capacity", settings_.queue_capacity},
          {"workers", scheduler_->workers()}};
}

std::string Service::metrics_text() const {
  Metrics::Gauges g;
  {
    std::lock_guard lock(mu_);
    for (auto& [id, j] : jobs_) {
      std::lock_guard jl(j->mu);
      ++g.jobs_by_state[std::string(to_string(j->state))];
    }
  }
  g.queue_depth = static_cast<long>(scheduler_->waiting());
  g.running = static_cast<long>(scheduler_->active());
  g.workers = scheduler_->workers();
  g.event_streams = streams_.load();
  g.waiting_requests = waiters_.load();
  g.cache_bytes = static_cast<long>(cache_.bytes());
  return metrics_.render_text(g);
}

void Service::shutdown() {
  if (shutting_down_.exchange(true)) return;
  scheduler_->drain(std::chrono::milliseconds(static_cast<long>(settings_.shutdown_grace * 1000)));
  scheduler_->stop();
  stopped_ = true;
  std::vector<std::shared_ptr<Job>> jobs;
  {
    std::lock_guard lock(mu_);
    for (auto& [id, j] : jobs_) jobs.push_back(j);
  }
  // Waiting requests and event streams wake up and see stopped().
  for (auto& j : jobs) {
    { std::lock_guard jl(j->mu); }
    j->changed.notify_all();
  }
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
