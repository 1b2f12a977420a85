// The job records of one process, in memory and in the results directory.
#include "local_job_store.h"

#include <algorithm>

#include "file_blob_store.h"

namespace rayfarm::server {
namespace fs = std::filesystem;

LocalJobStore::LocalJobStore(fs::path dir, BlobStore& blobs) : dir_(std::move(dir)), blobs_(blobs) {
  if (dir_.empty()) return;
  fs::create_directories(dir_ / "jobs");
  std::vector<JobRecord> found;
  for (auto& e : fs::directory_iterator(dir_ / "jobs")) {
    const std::string file = e.path().filename().string();
    if (e.path().extension() != ".json") continue;
    if (file.find(".tmp") != std::string::npos) continue;
    auto json = nlohmann::json::parse(read_whole_file(e.path()), nullptr, false);
    if (auto r = record_from_json(json); r && e.path().stem() == r->id)
      found.push_back(std::move(*r));  // a torn or foreign file is skipped
  }
  std::sort(found.begin(), found.end(), [](const JobRecord& a, const JobRecord& b) {
    return a.created_ms != b.created_ms ? a.created_ms < b.created_ms : a.id < b.id;
  });
  for (JobRecord& r : found) {
    r.sequence = ++sequence_;
    jobs_.emplace(r.id, std::move(r));
  }
}

void LocalJobStore::persist(const std::string& id) {
  if (dir_.empty() || !valid_blob_name(id)) return;
  std::lock_guard write(write_mu_);
  std::string text;
  {
    std::lock_guard lock(mu_);
    auto it = jobs_.find(id);
    if (it == jobs_.end()) return;  // expired meanwhile
    text = json_text(to_json(it->second));
  }
  write_atomically(dir_ / "jobs" / (id + ".json"), text);
}

void LocalJobStore::erase_files(const std::string& id) {
  if (dir_.empty() || !valid_blob_name(id)) return;
  std::lock_guard write(write_mu_);
  std::error_code ec;
  fs::remove(dir_ / "jobs" / (id + ".json"), ec);
  blobs_.remove(BlobKind::scene, id);
}

JobRecord LocalJobStore::create(JobRecord record, const std::string& scene_text) {
  {
    std::lock_guard lock(mu_);
    record.sequence = ++sequence_;
    ++record.version;
  }
  // On disk before anyone can see it: a job that was answered 202 survives a crash.
  if (!dir_.empty()) {
    if (!is_final(record.state)) blobs_.put(BlobKind::scene, record.id, scene_text);
    try {
      std::lock_guard write(write_mu_);
      if (valid_blob_name(record.id))
        write_atomically(dir_ / "jobs" / (record.id + ".json"), json_text(to_json(record)));
    } catch (...) {
      blobs_.remove(BlobKind::scene, record.id);
      throw;
    }
  }
  {
    std::lock_guard lock(mu_);
    jobs_[record.id] = record;
  }
  changed_.notify_all();
  return record;
}

std::optional<JobRecord> LocalJobStore::get(const std::string& id) const {
  std::lock_guard lock(mu_);
  auto it = jobs_.find(id);
  if (it == jobs_.end()) return std::nullopt;
  return it->second;
}

std::vector<JobRecord> LocalJobStore::list_by_client(const std::string& client,
                                                     size_t limit) const {
  std::vector<const JobRecord*> mine;
  std::lock_guard lock(mu_);
  for (auto& [id, r] : jobs_)
    if (r.client == client) mine.push_back(&r);
  std::sort(mine.begin(), mine.end(),
            [](const JobRecord* a, const JobRecord* b) { return a->sequence > b->sequence; });
  std::vector<JobRecord> out;
  for (size_t i = 0; i < mine.size() && i < limit; ++i) out.push_back(*mine[i]);
  return out;
}

std::optional<JobRecord> LocalJobStore::find_by_key(const std::string& client,
                                                    const std::string& key) const {
  if (key.empty()) return std::nullopt;
  std::lock_guard lock(mu_);
  const JobRecord* newest = nullptr;
  for (auto& [id, r] : jobs_)
    if (r.client == client && r.idempotency_key == key &&
        (!newest || r.sequence > newest->sequence))
      newest = &r;
  if (!newest) return std::nullopt;
  return *newest;
}

std::optional<JobRecord> LocalJobStore::transition(const std::string& id,
                                                   std::initializer_list<JobState> from,
                                                   const Patch& patch) {
  JobRecord after;
  {
    std::lock_guard lock(mu_);
    auto it = jobs_.find(id);
    if (it == jobs_.end()) return std::nullopt;
    if (std::find(from.begin(), from.end(), it->second.state) == from.end()) return std::nullopt;
    JobRecord changed = it->second;
    patch(changed);
    changed.id = it->second.id;  // what a record is about never changes
    changed.client = it->second.client;
    changed.sequence = it->second.sequence;
    changed.version = it->second.version + 1;
    it->second = changed;
    after = std::move(changed);
  }
  changed_.notify_all();
  try {
    persist(id);
  } catch (const std::exception&) {
    // The job goes on; after a restart it runs again from its last record, which is safe.
  }
  return after;
}

bool LocalJobStore::update_progress(const std::string& id, const RenderStats& stats) {
  {
    std::lock_guard lock(mu_);
    auto it = jobs_.find(id);
    if (it == jobs_.end() || is_final(it->second.state)) return false;
    it->second.stats = stats;
    ++it->second.version;
  }
  changed_.notify_all();
  return true;
}

std::optional<JobRecord> LocalJobStore::request_cancel(const std::string& id) {
  auto changed = transition(id, {JobState::queued, JobState::running},
                            [](JobRecord& r) { r.cancel_requested = true; });
  return changed ? changed : get(id);
}

std::optional<JobRecord> LocalJobStore::watch(const std::string& id, std::uint64_t since_version,
                                              Deadline deadline) const {
  std::unique_lock lock(mu_);
  auto it = jobs_.end();
  changed_.wait_until(lock, deadline, [&] {
    it = jobs_.find(id);
    return it == jobs_.end() || it->second.version > since_version;
  });
  it = jobs_.find(id);
  if (it == jobs_.end()) return std::nullopt;
  return it->second;
}

std::vector<JobRecord> LocalJobStore::expire(long long finished_before_ms) {
  std::vector<JobRecord> old;
  {
    std::lock_guard lock(mu_);
    for (auto it = jobs_.begin(); it != jobs_.end();) {
      if (is_final(it->second.state) && it->second.finished_ms < finished_before_ms) {
        old.push_back(std::move(it->second));
        it = jobs_.erase(it);
      } else {
        ++it;
      }
    }
  }
  if (!old.empty()) changed_.notify_all();
  for (const JobRecord& r : old) erase_files(r.id);
  return old;
}

void LocalJobStore::remove(const std::string& id) {
  {
    std::lock_guard lock(mu_);
    jobs_.erase(id);
  }
  changed_.notify_all();
  erase_files(id);
}

std::vector<JobRecord> LocalJobStore::all() const {
  std::vector<JobRecord> out;
  {
    std::lock_guard lock(mu_);
    out.reserve(jobs_.size());
    for (auto& [id, r] : jobs_) out.push_back(r);
  }
  std::sort(out.begin(), out.end(),
            [](const JobRecord& a, const JobRecord& b) { return a.sequence < b.sequence; });
  return out;
}

std::map<JobState, long> LocalJobStore::count_by_state() const {
  std::map<JobState, long> out;
  std::lock_guard lock(mu_);
  for (auto& [id, r] : jobs_) ++out[r.state];
  return out;
}

}  // namespace rayfarm::server
