// JobStore of one process: the records in memory, each change also written to the results
// directory (DIR/jobs/ID.json) when there is one, so a restart finds every accepted job.
#pragma once

#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <unordered_map>

#include "blob_store.h"
#include "job_store.h"

namespace rayfarm::server {

class LocalJobStore final : public JobStore {
 public:
  // Reads the records kept in `dir` (none without one); scene texts go to `blobs`.
  LocalJobStore(std::filesystem::path dir, BlobStore& blobs);

  JobRecord create(JobRecord record, const std::string& scene_text) override;
  std::optional<JobRecord> get(const std::string& id) const override;
  std::vector<JobRecord> list_by_client(const std::string& client, size_t limit) const override;
  std::optional<JobRecord> find_by_key(const std::string& client,
                                       const std::string& key) const override;
  std::optional<JobRecord> transition(const std::string& id, std::initializer_list<JobState> from,
                                      const Patch& patch) override;
  bool update_progress(const std::string& id, const RenderStats& stats) override;
  std::optional<JobRecord> request_cancel(const std::string& id) override;
  std::optional<JobRecord> watch(const std::string& id, std::uint64_t since_version,
                                 Deadline deadline) const override;
  std::vector<JobRecord> expire(long long finished_before_ms) override;
  void remove(const std::string& id) override;
  std::vector<JobRecord> all() const override;
  std::map<JobState, long> count_by_state() const override;

 private:
  // Writes the record as it is now (whoever writes last writes the newest).
  void persist(const std::string& id);
  void erase_files(const std::string& id);

  std::filesystem::path dir_;
  BlobStore& blobs_;
  mutable std::mutex mu_;
  mutable std::condition_variable changed_;
  std::unordered_map<std::string, JobRecord> jobs_;
  std::uint64_t sequence_ = 0;
  std::mutex write_mu_;  // one record file written at a time, after mu_ (never before)
};

}  // namespace rayfarm::server
