// The fair queue of one process.
#include "local_work_queue.h"

#include <algorithm>

namespace rayfarm::server {

void LocalWorkQueue::push(const QueueItem& item, bool front) {
  Class& cls = classes_[static_cast<int>(item.priority)];
  auto it = std::find_if(cls.begin(), cls.end(),
                         [&](const ClientJobs& c) { return c.client == item.client; });
  if (it == cls.end()) {
    // A client that had nothing queued is served after those already waiting (or first,
    // when its job was stopped and goes back).
    if (front) it = cls.insert(cls.begin(), ClientJobs{item.client, {}});
    else it = cls.insert(cls.end(), ClientJobs{item.client, {}});
  }
  if (front) it->jobs.push_front(item);
  else it->jobs.push_back(item);
}

void LocalWorkQueue::enqueue(const QueueItem& item) {
  std::lock_guard lock(mu_);
  push(item, false);
}

size_t LocalWorkQueue::active_of(const std::string& client) const {
  size_t n = 0;
  for (auto& [id, item] : active_) n += item.client == client;
  return n;
}

std::optional<QueueItem> LocalWorkQueue::claim(const std::string&, int max_active_per_client) {
  std::lock_guard lock(mu_);
  for (Class& cls : classes_) {
    for (auto it = cls.begin(); it != cls.end(); ++it) {
      if (active_of(it->client) >= static_cast<size_t>(std::max(1, max_active_per_client)))
        continue;
      QueueItem item = std::move(it->jobs.front());
      it->jobs.pop_front();
      ClientJobs served = std::move(*it);
      cls.erase(it);
      if (!served.jobs.empty()) cls.push_back(std::move(served));  // its turn comes round again
      active_[item.id] = item;
      return item;
    }
  }
  return std::nullopt;
}

void LocalWorkQueue::release(const std::string& id) {
  std::lock_guard lock(mu_);
  auto it = active_.find(id);
  if (it == active_.end()) return;
  push(it->second, true);
  active_.erase(it);
}

void LocalWorkQueue::complete(const std::string& id) {
  std::lock_guard lock(mu_);
  active_.erase(id);
}

bool LocalWorkQueue::remove(const std::string& id) {
  std::lock_guard lock(mu_);
  for (Class& cls : classes_)
    for (auto c = cls.begin(); c != cls.end(); ++c) {
      auto j = std::find_if(c->jobs.begin(), c->jobs.end(),
                            [&](const QueueItem& q) { return q.id == id; });
      if (j == c->jobs.end()) continue;
      c->jobs.erase(j);
      if (c->jobs.empty()) cls.erase(c);
      return true;
    }
  return false;
}

int LocalWorkQueue::position(const std::string& id) const {
  std::lock_guard lock(mu_);
  size_t ahead = 0;
  for (const Class& cls : classes_) {
    // Where the job is in its class: its client's place in the turn, its place in the client's
    // jobs. Round k serves the k-th job of every client, in turn order.
    size_t client_index = cls.size(), job_index = 0;
    for (size_t c = 0; c < cls.size() && client_index == cls.size(); ++c)
      for (size_t j = 0; j < cls[c].jobs.size(); ++j)
        if (cls[c].jobs[j].id == id) {
          client_index = c;
          job_index = j;
          break;
        }
    if (client_index == cls.size()) {
      for (const ClientJobs& c : cls) ahead += c.jobs.size();
      continue;
    }
    for (size_t c = 0; c < cls.size(); ++c)
      ahead += std::min(cls[c].jobs.size(), c < client_index ? job_index + 1 : job_index);
    return static_cast<int>(ahead) + 1;
  }
  return 0;
}

size_t LocalWorkQueue::depth() const {
  std::lock_guard lock(mu_);
  size_t n = 0;
  for (const Class& cls : classes_)
    for (const ClientJobs& c : cls) n += c.jobs.size();
  return n;
}

size_t LocalWorkQueue::active() const {
  std::lock_guard lock(mu_);
  return active_.size();
}

size_t LocalWorkQueue::jobs_of(const std::string& client) const {
  std::lock_guard lock(mu_);
  size_t n = active_of(client);
  for (const Class& cls : classes_)
    for (const ClientJobs& c : cls)
      if (c.client == client) n += c.jobs.size();
  return n;
}

}  // namespace rayfarm::server
