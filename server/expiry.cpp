// Expiry: finished jobs past the TTL, and the oldest images over the results size budget.
#include <vector>

#include "service.h"

namespace rayfarm::server {

void Service::expire() {
  const long long cutoff = now_ms() - static_cast<long long>(settings_.result_ttl * 1000);
  // The table is read from a snapshot, not under its lock: with many jobs kept the scan takes
  // a while, and submissions must not wait for it.
  std::vector<std::shared_ptr<Job>> kept;
  {
    std::lock_guard lock(mu_);
    kept.reserve(jobs_.size());
    for (auto& [id, j] : jobs_) kept.push_back(j);
  }
  std::vector<std::shared_ptr<Job>> old;
  for (auto& j : kept) {
    std::lock_guard jl(j->mu);
    if (is_final(j->state) && j->finished_ms < cutoff) old.push_back(j);
  }
  kept.clear();
  {
    std::lock_guard lock(mu_);
    for (auto& j : old) {
      jobs_.erase(j->id);
      auto it = image_refs_.find(j->image_name);
      if (it == image_refs_.end() || --it->second > 0) continue;
      image_refs_.erase(it);
      // Deleted under the lock: a new job takes its reference under it too.
      store_.remove_image(j->image_name);
      cache_.erase(j->image_name);
    }
  }
  for (auto& j : old) store_.remove_job(j->id);
  // Over the size budget: the oldest images go, and the jobs that pointed at them.
  auto images = store_.images_oldest_first();
  std::uintmax_t total = 0;
  for (auto& [name, size] : images) total += size;
  for (auto& [name, size] : images) {
    if (total <= settings_.results_max_bytes) break;
    store_.remove_image(name);
    cache_.erase(name);
    total -= size;
  }
}

}  // namespace rayfarm::server
