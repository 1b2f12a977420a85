// The render pool: worker threads that start jobs in the WorkQueue's fair order and take tiles
// from the started ones, round-robin over clients and, within a client, over its active jobs.
// A job alone gets every worker; a small job behind a big one gets its share at once. Renders
// never run on HTTP threads.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <vector>

#include "job.h"
#include "work_queue.h"

namespace rayfarm::server {

class Scheduler {
 public:
  struct Hooks {
    // The render is prepared: the job's record becomes running. False when the job may not
    // run any more (canceled meanwhile): the render stops.
    std::function<bool(Job&, const RenderStats&)> started;
    std::function<void(Job&, const RenderStats&)> progress;
    // Exactly once per job: the render ended (`render` null when canceled while queued, or
    // when the scene could not be prepared: then the job's error is set).
    std::function<void(Job&, RenderJob* render)> finished;
  };

  Scheduler(WorkQueue& queue, std::string node, int workers, int max_active_per_client,
            double job_timeout_s, Hooks hooks);
  ~Scheduler();

  void submit(std::shared_ptr<Job> job);
  // Cancels a queued job at once or asks a running one to stop. False if not in the pool.
  bool cancel(const std::string& id);
  // The render in progress of a job this process runs (null otherwise).
  std::shared_ptr<RenderJob> render_of(const std::string& id) const;
  size_t active() const;
  // A shutdown's grace period is over: the renders it stopped are to run again after a restart.
  bool interrupted() const { return interrupt_.load(); }
  int workers() const { return static_cast<int>(threads_.size()); }

  // Shutdown: no queued job starts any more; returns when running renders ended or the
  // grace period passed (then they are canceled).
  void drain(std::chrono::milliseconds grace);
  void stop();

 private:
  struct Entry {
    std::shared_ptr<Job> job;
    bool preparing = false;
    std::uint64_t blocked_epoch = ~0ULL;  // its pass waits for tiles in flight
  };
  struct Client {
    std::string name;
    std::deque<Entry> entries;
    size_t next = 0;
  };
  struct Pick {
    std::shared_ptr<Job> job;
    bool prepare = false;
    std::uint64_t epoch = 0;
  };

  void work();
  std::optional<Pick> pick();
  void prepare(const std::shared_ptr<Job>& job);
  void remove_and_finish(const std::shared_ptr<Job>& job, RenderJob* render);
  Entry* find(const Job& job);
  void after_tile(const std::shared_ptr<Job>& job, RenderJob& render);

  WorkQueue& queue_;
  const std::string node_;
  const int max_active_per_client_;
  const double job_timeout_s_;
  Hooks hooks_;

  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::vector<Client> clients_;  // the started jobs
  std::unordered_map<std::string, std::shared_ptr<Job>> queued_;  // in queue_, by id
  size_t next_client_ = 0;
  std::uint64_t tile_epoch_ = 0;
  bool paused_ = false;
  std::atomic<bool> interrupt_{false};  // the grace period is over: running renders stop
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace rayfarm::server
