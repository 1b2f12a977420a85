// Starting jobs in the queue's order, and fair tile scheduling over the started ones.
#include "scheduler.h"

#include <algorithm>

namespace rayfarm::server {

Scheduler::Scheduler(WorkQueue& queue, std::string node, int workers, int max_active_per_client,
                     double job_timeout_s, Hooks hooks)
    : queue_(queue),
      node_(std::move(node)),
      max_active_per_client_(std::max(1, max_active_per_client)),
      job_timeout_s_(job_timeout_s),
      hooks_(std::move(hooks)) {
  for (int i = 0; i < std::max(1, workers); ++i) threads_.emplace_back([this] { work(); });
}

Scheduler::~Scheduler() { stop(); }

void Scheduler::submit(std::shared_ptr<Job> job) {
  {
    std::lock_guard lock(mu_);
    QueueItem item{job->id, job->client, job->priority};
    queued_[job->id] = std::move(job);
    queue_.enqueue(item);
  }
  cv_.notify_all();
}

Scheduler::Entry* Scheduler::find(const Job& job) {
  for (Client& c : clients_)
    for (Entry& e : c.entries)
      if (e.job.get() == &job) return &e;
  return nullptr;
}

bool Scheduler::cancel(const std::string& id) {
  std::shared_ptr<Job> removed;
  std::shared_ptr<RenderJob> render;
  {
    std::lock_guard lock(mu_);
    if (auto it = queued_.find(id); it != queued_.end() && queue_.remove(id)) {
      removed = it->second;
      removed->cancel_requested = true;
      queued_.erase(it);
    } else {
      Entry* e = nullptr;
      for (Client& c : clients_)
        for (Entry& x : c.entries)
          if (x.job->id == id) e = &x;
      if (!e) return false;
      // Running, or being prepared (then prepare() sees cancel_requested).
      e->job->cancel_requested = true;
      std::lock_guard jl(e->job->mu);
      render = e->job->render;
    }
  }
  if (removed) hooks_.finished(*removed, nullptr);
  else if (render) render->cancel();
  cv_.notify_all();
  return true;
}

std::shared_ptr<RenderJob> Scheduler::render_of(const std::string& id) const {
  std::lock_guard lock(mu_);
  for (const Client& c : clients_)
    for (const Entry& e : c.entries)
      if (e.job->id == id) {
        std::lock_guard jl(e.job->mu);
        return e.job->render;
      }
  return nullptr;
}

size_t Scheduler::active() const {
  std::lock_guard lock(mu_);
  size_t n = 0;
  for (const Client& c : clients_) n += c.entries.size();
  return n;
}

// Under mu_: a job to start when the queue has one this node may take, else the next job to
// give a tile, round-robin over clients then over the client's jobs.
std::optional<Scheduler::Pick> Scheduler::pick() {
  if (!paused_)
    while (auto item = queue_.claim(node_, max_active_per_client_)) {
      auto it = queued_.find(item->id);
      if (it == queued_.end()) {
        // Not a job this process accepted: the local queue holds none. A queue shared by
        // several processes needs the job built here from its record and scene instead.
        queue_.complete(item->id);
        continue;
      }
      std::shared_ptr<Job> job = std::move(it->second);
      queued_.erase(it);
      auto c = std::find_if(clients_.begin(), clients_.end(),
                            [&](const Client& x) { return x.name == job->client; });
      if (c == clients_.end()) {
        clients_.push_back({job->client, {}, 0});
        c = clients_.end() - 1;
      }
      c->entries.push_back({job, true});
      return Pick{job, true, tile_epoch_};
    }
  const size_t n = clients_.size();
  for (size_t ci = 0; ci < n; ++ci) {
    Client& c = clients_[(next_client_ + ci) % n];
    const size_t m = c.entries.size();
    for (size_t ei = 0; ei < m; ++ei) {
      size_t index = (c.next + ei) % m;
      Entry& e = c.entries[index];
      if (e.preparing || e.blocked_epoch == tile_epoch_) continue;
      next_client_ = (next_client_ + ci + 1) % n;
      c.next = index + 1;
      return Pick{e.job, false, tile_epoch_};
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
  if (!render) {
    {
      std::lock_guard jl(job->mu);
      job->error = error;
      job->error_code = "bad_request";
    }
    remove_and_finish(job, nullptr);
    return;
  }
  {
    std::lock_guard jl(job->mu);
    job->render = render;
  }
  // A cancel or a shutdown that came while the scene was being prepared.
  if (!hooks_.started(*job, render->stats()) || job->cancel_requested || interrupt_.load())
    render->cancel();
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
    queue_.complete(job->id);
  }
  hooks_.finished(*job, render);
  {
    std::lock_guard jl(job->mu);
    job->render.reset();
  }
  cv_.notify_all();
}

void Scheduler::after_tile(const std::shared_ptr<Job>& job, RenderJob& render) {
  // The job's own time: its tiles' time over the threads, what it takes alone on this node.
  const double own_s = 1e-9 * static_cast<double>(job->render_ns.load()) / workers();
  if (job_timeout_s_ > 0 && own_s > job_timeout_s_) {
    job->timed_out = true;
    render.cancel();
  }
  if (hooks_.progress) hooks_.progress(*job, render.stats());
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
    const auto tile_start = std::chrono::steady_clock::now();
    try {
      step = render->run_step();
      p->job->render_ns += std::chrono::duration_cast<std::chrono::nanoseconds>(
                               std::chrono::steady_clock::now() - tile_start)
                               .count();
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
      for (Entry& e : c.entries) {
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
