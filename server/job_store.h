// The job records of the service: one interface, today's local store behind it (and a shared
// store for several nodes later). Every change of a job's state is a compare-and-set through
// transition(); waiting for a job is watch(), never a lock on its internals.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "job_record.h"

namespace rayfarm::server {

class JobStore {
 public:
  using Deadline = std::chrono::steady_clock::time_point;
  // Changes a record in place. A store may call it more than once (an optimistic retry), so
  // it must depend on nothing but the record it is given.
  using Patch = std::function<void(JobRecord&)>;

  virtual ~JobStore() = default;

  // Adds a record with its scene text; both are durable when it returns (before the 202).
  // Gives the record its sequence and returns it. Throws std::runtime_error when the storage
  // refuses; then nothing was added.
  virtual JobRecord create(JobRecord record, const std::string& scene_text) = 0;
  virtual std::optional<JobRecord> get(const std::string& id) const = 0;
  // The client's jobs, newest first, at most `limit`.
  virtual std::vector<JobRecord> list_by_client(const std::string& client,
                                                size_t limit) const = 0;
  // The client's job made with this Idempotency-Key, if it is still kept.
  virtual std::optional<JobRecord> find_by_key(const std::string& client,
                                               const std::string& key) const = 0;
  // Compare-and-set: applies `patch` only if the job's state is one of `from`, bumps the
  // version and (for a durable store) persists. Returns the new record, or nullopt when the
  // job is unknown or in another state: of two racing transitions from a state, one wins.
  virtual std::optional<JobRecord> transition(const std::string& id,
                                              std::initializer_list<JobState> from,
                                              const Patch& patch) = 0;
  // The render's progress: bumps the version, not persisted. False when the job is final.
  virtual bool update_progress(const std::string& id, const RenderStats& stats) = 0;
  // Marks an unfinished job as asked to stop (persisted; the renderer polls it). Returns the
  // record after the change, or as it is when it is already final; nullopt when unknown.
  virtual std::optional<JobRecord> request_cancel(const std::string& id) = 0;
  // Returns the record once its version is above `since_version` (at once if it already is),
  // or as it is at the deadline; nullopt when the job is unknown (or expired meanwhile).
  virtual std::optional<JobRecord> watch(const std::string& id, std::uint64_t since_version,
                                         Deadline deadline) const = 0;
  // Removes final jobs that finished before `finished_before_ms` with their scene texts;
  // returns what it removed (the caller releases their images).
  virtual std::vector<JobRecord> expire(long long finished_before_ms) = 0;
  // Removes a job at once (a restored record whose image has gone).
  virtual void remove(const std::string& id) = 0;
  // Every record, oldest first: for the start of a process and tests; O(jobs).
  virtual std::vector<JobRecord> all() const = 0;
  virtual std::map<JobState, long> count_by_state() const = 0;
};

}  // namespace rayfarm::server
