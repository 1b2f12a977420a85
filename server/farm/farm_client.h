// The farm's shared state in Redis, as typed calls: each is one FCALL of the rayfarm1
// Function library (rayfarm1.lua, which documents the contract of every function), so each
// transition is atomic and idempotent. Plain structs in, plain structs and enums out; Redis
// errors as values (redis_error.h).
//
// A FarmClient is a view over one Connection and is used by that connection's thread only.
// Install farm_setup()'s hook in the ConnectOptions of every farm connection: on each
// (re)connect it loads the library, creates the consumer group and checks the build and the
// epoch (a changed epoch means Redis came back without its data).
#pragma once

#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "redis_connection.h"

namespace rayfarm::farm {

struct FarmConfig {
  std::string prefix = "rf:";  // every key and channel of the farm starts with it
  std::string node;            // consumer name: unique per process start (host:port:pid:boot)
  std::string build;           // nodes of another build are refused (bytes must match)
  int feed_target = 8;         // undelivered units kept in the work stream (≈ Σ live threads)
  int max_tries = 3;           // a unit abandoned or failed this often fails its job
  std::chrono::milliseconds block{1000};  // block_for_work's XREADGROUP BLOCK
};

// The library's source (rayfarm1.lua), built into the binary.
std::string_view function_library();

// What every farm connection does after connecting. Shared by a node's connections.
class FarmSetup {
 public:
  explicit FarmSetup(FarmConfig config) : config_(std::move(config)) {}
  Status on_connect(Connection& c);
  // The epoch this node joined, and how often a reconnect found another one (Redis restarted
  // empty or from an older file: journaled jobs must be re-registered).
  std::string epoch() const;
  int epoch_changes() const { return epoch_changes_.load(); }

 private:
  FarmConfig config_;
  mutable std::mutex mutex_;
  std::string epoch_;
  std::atomic<int> epoch_changes_{0};
};

// Connect options for a farm connection: `base` plus the setup hook.
ConnectOptions farm_connect_options(ConnectOptions base, std::shared_ptr<FarmSetup> setup);

// Creates the work stream's consumer group (an existing group is fine).
Status create_work_group(Connection& c, std::string_view prefix);

enum class Priority { Interactive = 0, Normal = 1, Batch = 2 };

struct SubmitRequest {
  std::string job;
  std::string client;
  Priority priority = Priority::Normal;
  int units = 1;  // 0: a local job, rendered by the accepting node and ended with record()
  std::string opts;
  std::string idempotency_key;  // empty: none; else the same key of a client gives the same job
  int max_active_per_client = 8;
  int max_jobs = 0;  // queued + running jobs across the farm; 0: no limit
  std::chrono::milliseconds ttl{std::chrono::hours(1)};  // the record's life after it ends
  std::chrono::milliseconds idempotency_ttl{std::chrono::hours(24)};
  // The job fails this long after it starts running (the sweep); 0: no limit.
  std::chrono::milliseconds timeout{0};
  std::vector<std::pair<std::string, std::string>> fields;  // more fields for the job record
};
enum class SubmitStatus { Accepted, Exists, ClientLimit, Full };
struct SubmitResult {
  SubmitStatus status;
  std::string job;  // for Exists through an idempotency key: the job that key gave first
};

// A unit a node holds: the stream entry (its lease), the job, the unit index, how often it was
// tried before, and the job's opts.
struct Unit {
  std::string entry;
  std::string job;
  int index = 0;
  int tries = 0;
  std::string opts;
};

enum class CompleteStatus { Stored, Duplicate, Dropped, Assemble };
enum class FailStatus { Requeued, JobFailed, Dropped, Gone };
enum class ReleaseStatus { Requeued, Dropped, Gone };
struct ReclaimResult {
  std::string cursor;  // "0-0" when the sweep went round the whole backlog
  int requeued = 0;
  int failed = 0;  // jobs failed because a unit reached max_tries
};
// The farm's jobs by state and its live nodes (rf1_counts).
struct FarmCounts {
  long long queued = 0, running = 0, assembling = 0, nodes = 0;
};
// What rf1_sweep did with the jobs no unit lease covers.
struct SweepResult {
  int timed_out = 0;  // failed: running past its own limit (SubmitRequest::timeout)
  int orphaned = 0;   // failed: a local job whose node is gone
  std::vector<std::string> assemble;  // their assembler is gone: this janitor assembles them
};
enum class CancelStatus { Canceled, NotFound, Forbidden, AlreadyEnded };
struct CancelResult {
  CancelStatus status;
  std::string state;  // the job's state (for AlreadyEnded: done, failed or canceled)
};
enum class FinishStatus { Done, AlreadyDone, NotAssembling };
struct FinishResult {
  FinishStatus status;
  std::string state;
};
enum class EndState { Done, Failed, Canceled };
using Fields = std::vector<std::pair<std::string, std::string>>;
struct RecordRequest {
  std::string job;
  std::string client;
  Priority priority = Priority::Normal;
  EndState state = EndState::Done;
  std::string result;  // result key (the PNG), when done
  std::string error;   // when failed
  std::chrono::milliseconds ttl{std::chrono::hours(1)};
  Fields fields;  // more fields for the job record (stats)
};
enum class RecordStatus { Recorded, Exists, Forbidden };
struct JoinResult {
  std::string epoch;
  bool created = false;  // this call started the farm (or Redis had lost its data)
};
using JobFields = std::map<std::string, std::string>;

class FarmClient {
 public:
  FarmClient(Connection& connection, FarmConfig config)
      : c_(connection), config_(std::move(config)) {}

  // Checks the build (rf:meta:build; the first node sets it) and reads the epoch
  // (rf:meta:epoch), setting it to `fresh_epoch` when Redis has none. Plain commands, not a
  // Function: it runs before the library is loaded.
  Result<JoinResult> join(std::string_view fresh_epoch);
  Result<SubmitResult> submit(const SubmitRequest& request);
  // Feeds the stream fairly and hands this node the next wanted unit, or nullopt.
  Result<std::optional<Unit>> take();
  // Waits up to config.block for an entry (XREADGROUP BLOCK may not run inside a Function),
  // then checks it like take() (rf1_adopt). nullopt after the wait: call take() again.
  Result<std::optional<Unit>> block_for_work();
  // Renews the leases of `entries`; returns those that were reclaimed (stop rendering them).
  Result<std::vector<std::string>> heartbeat(std::string_view node_info,
                                             std::chrono::milliseconds ttl,
                                             const std::vector<std::string>& entries);
  Result<CompleteStatus> complete(const Unit& unit, std::string_view payload);
  Result<FailStatus> fail(const Unit& unit, std::string_view error);
  Result<ReleaseStatus> release(const Unit& unit);
  // The entries this node holds according to Redis (its PEL), oldest first. After a take whose
  // reply was lost (a timeout), Redis holds an entry the node does not know: release those, or
  // the reclaim would count a try the unit never had.
  Result<std::vector<std::string>> held_entries(int count = 100);
  Result<ReclaimResult> reclaim(std::string_view janitor, std::chrono::milliseconds lease,
                                std::string_view cursor = "0-0", int count = 64);
  Result<SweepResult> sweep(std::string_view janitor, std::chrono::milliseconds lease,
                            int count = 100);
  Result<CancelResult> cancel(std::string_view job, std::string_view client);
  Result<FarmCounts> counts();
  Result<FinishResult> finish(std::string_view job, std::string_view result_key,
                              const Fields& fields = {});
  Result<RecordStatus> record(const RecordRequest& request);
  // True when this node holds the janitor lock for the next `hold` (taken or renewed).
  Result<bool> janitor_lock(std::chrono::milliseconds hold);
  // Records how far (0-1000) this node's render of a local job has got; false when the job
  // is not a local job of this node's that is running.
  Result<bool> progress(std::string_view job, int permille);

  // Whether a running node of this farm has this client's node name: its record (node:NAME,
  // which each heartbeat sets with a time to live of three heartbeats) is renewed before it
  // runs out, as the farm judges a node alive. A record left by a node that stopped (killed,
  // or restarted under the same name) runs out instead: false then, after its rest of life.
  // No record: false at once. Plain commands: it may run before the library is loaded.
  Result<bool> node_running();

  // The job's record, or nullopt when there is none.
  Result<std::optional<JobFields>> job(std::string_view id);
  // Stored unit results 0..units-1 (nullopt where none), read `chunk` at a time.
  Result<std::vector<std::optional<std::string>>> tiles(std::string_view job, int units,
                                                        int chunk = 256);

  std::string key(std::string_view name) const { return config_.prefix + std::string(name); }
  const FarmConfig& config() const { return config_; }
  Connection& connection() { return c_; }

 private:
  Result<Reply> fcall(std::string_view function, std::vector<std::string_view> args);
  Result<std::optional<Unit>> unit_reply(Result<Reply> r);

  Connection& c_;
  FarmConfig config_;
};

}  // namespace rayfarm::farm
