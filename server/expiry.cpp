// Expiry: finished jobs past the TTL, and the oldest images over the results size budget.
#include <set>

#include "service.h"

namespace rayfarm::server {

void Service::expire() {
  const long long cutoff = now_ms() - static_cast<long long>(settings_.result_ttl * 1000);
  std::vector<std::shared_ptr<Job>> old;
  {
    std::lock_guard lock(mu_);
    for (auto it = jobs_.begin(); it != jobs_.end();) {
      bool expired;
      {
        std::lock_guard jl(it->second->mu);
        expired = is_final(it->second->state) && it->second->finished_ms < cutoff;
      }
      if (expired) {
        old.push_back(it->second);
        it = jobs_.erase(it);
      } else {
        ++it;
      }
    }
  }
  std::set<std::string> referenced;
  {
    std::lock_guard lock(mu_);
    for (auto& [id, j] : jobs_) referenced.insert(j->image_name);
  }
  for (auto& j : old) {
    store_.remove_job(j->id);
    if (!referenced.count(j->image_name)) {
      store_.remove_image(j->image_name);
      cache_.erase(j->image_name);
    }
  }
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
