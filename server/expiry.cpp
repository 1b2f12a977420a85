// Expiry: finished jobs past the TTL, and the oldest images over the results size budget.
#include <vector>

#include "service.h"

namespace rayfarm::server {

void Service::release_image(const std::string& name) {
  std::lock_guard lock(mu_);
  auto it = image_refs_.find(name);
  if (it == image_refs_.end() || --it->second > 0) return;
  image_refs_.erase(it);
  // Deleted under the lock: a new job takes its reference under it too.
  blobs_.remove(BlobKind::image, name);
  cache_.erase(name);
}

void Service::expire() {
  const long long cutoff = now_ms() - static_cast<long long>(settings_.result_ttl * 1000);
  for (const JobRecord& old : jobs_->expire(cutoff)) release_image(old.image_name);
  // Over the size budget: the oldest images go, and the jobs that pointed at them.
  auto images = blobs_.oldest_first(BlobKind::image);
  std::uintmax_t total = 0;
  for (auto& [name, size] : images) total += size;
  for (auto& [name, size] : images) {
    if (total <= settings_.results_max_bytes) break;
    blobs_.remove(BlobKind::image, name);
    cache_.erase(name);
    total -= size;
  }
}

}  // namespace rayfarm::server
