// Fair tile scheduling over jobs and clients.
#include "scheduler.h"

#include <algorithm>

namespace rayfarm::server {

Scheduler::Scheduler(int workers, int max_active_per_client, double job_timeout_s, Hooks hooks)
    : max_active_per_client_(std::max(1, max_active_per_client)),
      job_timeout_s_(job_timeout_s),
      hooks_(std::move(hooks)) {
  for (int i = 0; i < std::max(1, workers); ++i) threads_.emplace_back([this] { work(); });
}

Scheduler::~Scheduler() { stop(); }

void Scheduler::submit(std::shared_ptr<Job> job) {
  {
    std::lock_guard lock(mu_);
    auto it = std::find_if(clients_.begin(), clients_.end(),
                           [&](const Client& c) { return c.name == job->client; });
    if (it == clients_.end()) {
      clients_.push_back({job->client, {}, 0});
      it = clients_.end() - 1;
    }
    it->entries.push_back({std::move(job)});
  }
  cv_.notify_all();
}

Scheduler::Entry* Scheduler::find(const Job& job) {
  for (Client& c : clients_)
    for (Entry& e : c.entries)
      if (e.job.get() == &job) return &e;
  return nullptr;
}

bool Scheduler::cancel(const std::shared_ptr<Job>& job) {
  std::shared_ptr<RenderJob> render;
  bool removed = false;
  {
    std::lock_guard lock(mu_);
    Entry* e = find(*job);
    if (!e) return false;
    job->cancel_requested = true;
    if (e->active) {
      // Running, or being prepared (then prepare() sees cancel_requested).
      std::lock_guard jl(job->mu);
      render = job->render;
    } else {
      for (Client& c : clients_)
        std::erase_if(c.entries, [&](const Entry& x) { return x.job == job; });
      std::erase_if(clients_, [](const Client& c) { return c.entries.empty(); });
      removed = true;
    }
  }
  if (removed) hooks_.finished(*job, nullptr);
  else if (render) render->cancel();
  cv_.notify_all();
  return true;
}

int Scheduler::queue_position(const Job& job) const {
  std::lock_guard lock(mu_);
  int ahead = 0;
  bool found = false;
  for (const Client& c : clients_)
    for (const Entry& e : c.entries) {
      if (e.job.get() == &job) found = !e.active;
      else if (!e.active && e.job->sequence < job.sequence) ++ahead;
    }
  return found ? ahead + 1 : 0;
}

size_t Scheduler::waiting() const {
  std::lock_guard lock(mu_);
  size_t n = 0;
  for (const Client& c : clients_)
    for (const Entry& e : c.entries) n += !e.active;
  return n;
}

size_t Scheduler::jobs_of(const std::string& client) const {
  std::lock_guard lock(mu_);
  for (const Client& c : clients_)
    if (c.name == client) return c.entries.size();
  return 0;
}

size_t Scheduler::active() const {
  std::lock_guard lock(mu_);
  size_t n = 0;
  for (const Client& c : clients_)
    for (const Entry& e : c.entries) n += e.active;
  return n;
}

// Under mu_: the next job to give a tile, round-robin over clients then over the client's
// jobs. Jobs of a client start in submission order, a few at a time.
std::optional<Scheduler::Pick> Scheduler::pick() {
  const size_t n = clients_.size();
  for (size_t ci = 0; ci < n; ++ci) {
    Client& c = clients_[(next_client_ + ci) % n];
    int active = 0;
    for (const Entry& e : c.entries) active += e.active;
    const size_t m = c.entries.size();
    for (size_t ei = 0; ei < m; ++ei) {
      size_t index = (c.next + ei) % m;
      Entry& e = c.entries[index];
      bool runnable = e.active && !e.preparing && e.blocked_epoch != tile_epoch_;
      bool startable = !e.active && !paused_ && active < max_active_per_client_;
      // Queued jobs of a client start in order: only the first waiting one may start.
      if (!e.active && !startable) continue;
      if (!runnable && !startable) continue;
      if (startable) {
        bool earlier_waiting = false;
        for (size_t k = 0; k < index; ++k) earlier_waiting |= !c.entries[k].active;
        if (earlier_waiting) continue;
        e.active = true;
        e.preparing = true;
      }
      next_client_ = (next_client_ + ci + 1) % n;
      c.next = index + 1;
      return Pick{e.job, startable, tile_epoch_};
    }
  }
  return std::nullopt;
}

void Scheduler::prepare(const std::shared_ptr<Job>& job) {
  std::string error;
  std::shared_ptr<RenderJob> render;
  try {
    render = RenderJob::create(*job->scene, job->options, &error);
  } catch (const std::exception& e) {
    error = std::string("could not prepare the scene: ") + e.what();
  }
  {
    std::lock_guard jl(job->mu);
    if (render) {
      job->render = render;
      job->state = JobState::running;
      job->started_ms = now_ms();
      job->run_start = std::chrono::steady_clock::now();
      job->stats = render->stats();
    } else {
      job->error = error;
      job->error_code = "bad_request";
    }
    ++job->attempts;
    ++job->version;
  }
  job->changed.notify_all();
  if (!render) {
    remove_and_finish(job, nullptr);
    return;
  }
  // A cancel or a shutdown that came while the scene was being prepared.
  if (job->cancel_requested || interrupt_.load()) render->cancel();
  if (hooks_.started) hooks_.started(*job);
  std::lock_guard lock(mu_);
  if (Entry* e = find(*job)) e->preparing = false;
}

void Scheduler::remove_and_finish(const std::shared_ptr<Job>& job, RenderJob* render) {
  {
    std::lock_guard lock(mu_);
    bool present = false;
    for (Client& c : clients_)
      present |= std::erase_if(c.entries, [&](const Entry& x) { return x.job == job; }) > 0;
    std::erase_if(clients_, [](const Client& c) { return c.entries.empty(); });
    if (!present) return;  // another worker finished it
  }
  hooks_.finished(*job, render);
  cv_.notify_all();
}

void Scheduler::after_tile(const std::shared_ptr<Job>& job, RenderJob& render) {
  {
    std::lock_guard jl(job->mu);
    // Another worker may have finished the job meanwhile: its final stats stand.
    if (is_final(job->state)) return;
    job->stats = render.stats();
    ++job->version;
    if (job_timeout_s_ > 0 && std::chrono::steady_clock::now() - job->run_start >
                                  std::chrono::duration<double>(job_timeout_s_)) {
      job->timed_out = true;
      render.cancel();
    }
  }
  job->changed.notify_all();
  if (hooks_.progress) hooks_.progress(*job);
}

void Scheduler::work() {
  for (;;) {
    std::optional<Pick> p;
    {
      std::unique_lock lock(mu_);
      for (;;) {
        if (stopping_) return;
        p = pick();
        if (p) break;
        cv_.wait_for(lock, std::chrono::milliseconds(50));
      }
    }
    if (p->prepare) {
      prepare(p->job);
      continue;
    }
    std::shared_ptr<RenderJob> render;
    {
      std::lock_guard jl(p->job->mu);
      render = p->job->render;
    }
    // Another worker finished the job between pick() and here (the render is dropped then).
    if (!render) continue;
    RenderJob::Step step;
    try {
      step = render->run_step();
    } catch (const std::exception& e) {
      {
        std::lock_guard jl(p->job->mu);
        p->job->error = std::string("render failed: ") + e.what();
        p->job->error_code = "render_failed";
      }
      render->cancel();
      step = RenderJob::Step::done;
    }
    if (step == RenderJob::Step::ran) {
      {
        std::lock_guard lock(mu_);
        ++tile_epoch_;
      }
      cv_.notify_all();
      after_tile(p->job, *render);
      if (render->finished()) remove_and_finish(p->job, render.get());
    } else if (step == RenderJob::Step::wait) {
      std::lock_guard lock(mu_);
      if (Entry* e = find(*p->job)) e->blocked_epoch = p->epoch;
    } else {
      remove_and_finish(p->job, render.get());
    }
  }
}

void Scheduler::drain(std::chrono::milliseconds grace) {
  auto deadline = std::chrono::steady_clock::now() + grace;
  {
    std::lock_guard lock(mu_);
    paused_ = true;
  }
  for (;;) {
    if (active() == 0) return;
    if (std::chrono::steady_clock::now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::vector<std::shared_ptr<RenderJob>> running;
  interrupt_ = true;  // renders being prepared now are canceled as they start
  {
    std::lock_guard lock(mu_);
    for (Client& c : clients_)
      for (Entry& e : c.entries)
        if (e.active) {
          std::lock_guard jl(e.job->mu);
          if (e.job->render) running.push_back(e.job->render);
        }
  }
  for (auto& r : running) r->cancel();
  while (active() > 0 && std::chrono::steady_clock::now() < deadline + std::chrono::seconds(5))
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
}

void Scheduler::stop() {
  {
    std::lock_guard lock(mu_);
    if (stopping_) return;
    stopping_ = true;
  }
  cv_.notify_all();
  for (auto& t : threads_)
    if (t.joinable()) t.join();
}

}  // namespace rayfarm::server
