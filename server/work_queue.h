// Which job starts next: one interface, today's in-process queue behind it (a shared queue
// for several nodes later). The order is fair: a higher priority class first, strictly; within
// a class, clients in turn (round robin); a client's own jobs in the order it sent them.
// Tiles of the jobs a node has started are shared out by its Scheduler, not here.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "job_record.h"

namespace rayfarm::server {

inline constexpr int kPriorities = 3;  // the classes of Priority, served in its order

struct QueueItem {
  std::string id;
  std::string client;
  Priority priority = Priority::normal;
};

class WorkQueue {
 public:
  virtual ~WorkQueue() = default;

  virtual void enqueue(const QueueItem& item) = 0;
  // The next job in the fair order, skipping clients that have `max_active_per_client` jobs
  // claimed and not completed. The job then counts as active (for `node`) until complete()
  // or release(). Nullopt when nothing may start.
  virtual std::optional<QueueItem> claim(const std::string& node, int max_active_per_client) = 0;
  // An active job goes back to the front of its client's jobs (its node stopped it).
  virtual void release(const std::string& id) = 0;
  // An active job ended.
  virtual void complete(const std::string& id) = 0;
  // A queued job leaves without starting (canceled). False when it is not queued.
  virtual bool remove(const std::string& id) = 0;

  // 1-based place in the order claims would take (ignoring the per-client limit); 0 when the
  // job is not queued.
  virtual int position(const std::string& id) const = 0;
  virtual size_t depth() const = 0;   // queued
  virtual size_t active() const = 0;  // claimed, not completed
  // Queued or active jobs of a client (what the per-client limit counts).
  virtual size_t jobs_of(const std::string& client) const = 0;
};

}  // namespace rayfarm::server
