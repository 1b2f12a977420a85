// The WorkQueue of one process: per priority class, the clients with queued jobs in the order
// they are served next (a served client goes to the back), each with its jobs in order.
#pragma once

#include <array>
#include <deque>
#include <mutex>
#include <unordered_map>

#include "work_queue.h"

namespace rayfarm::server {

class LocalWorkQueue final : public WorkQueue {
 public:
  void enqueue(const QueueItem& item) override;
  std::optional<QueueItem> claim(const std::string& node, int max_active_per_client) override;
  void release(const std::string& id) override;
  void complete(const std::string& id) override;
  bool remove(const std::string& id) override;
  int position(const std::string& id) const override;
  size_t depth() const override;
  size_t active() const override;
  size_t jobs_of(const std::string& client) const override;

 private:
  struct ClientJobs {
    std::string client;
    std::deque<QueueItem> jobs;
  };
  using Class = std::deque<ClientJobs>;

  void push(const QueueItem& item, bool front);
  size_t active_of(const std::string& client) const;

  mutable std::mutex mu_;
  std::array<Class, kPriorities> classes_;
  std::unordered_map<std::string, QueueItem> active_;  // by id
};

}  // namespace rayfarm::server
