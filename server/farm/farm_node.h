// A node of the render farm: worker threads that take units (ranges of tiles) of any node's
// jobs from Redis, render them and hand the results back; the node that completes a job's
// last unit puts the image together, stores the PNG and ends the job. A heartbeat thread
// renews the leases of the units being rendered, stops the ones whose job was canceled or
// whose lease was lost, and (on the node holding the janitor lock) hands abandoned units to
// other nodes. Nothing is owned by a node: a node that dies loses no job.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "farm_client.h"
#include "rayfarm/options.h"
#include "rayfarm/render.h"
#include "rayfarm/scene.h"

namespace rayfarm::farm {

// What every node needs to render any unit of a job, kept in the job's `opts` field.
struct FarmJob {
  std::string scene;  // the scene text's key (its SHA-256), under PREFIX scene:
  std::vector<std::pair<std::string, std::string>> options;  // option_pairs()
  int width = 0, height = 0;
  int tiles_per_unit = 1;
  int units = 1;
  std::string result;  // the PNG's key, under PREFIX png:

  std::string to_json() const;
  static std::optional<FarmJob> from_json(std::string_view text, std::string* error);
  TileRange unit_range(int index) const;
};

// Stores the scene text (once per content) and submits the job: everything a node needs to
// render it. `unit_work`: the work a unit should take, in samples × (bounces + 1) per pixel.
struct FarmSubmission {
  std::string job;
  std::string client;
  Priority priority = Priority::Normal;
  std::string scene_text;
  RenderOptions options;   // width and height set (the camera's, when 0 was asked)
  std::string result_key;  // content key of the image, or the job id
  double unit_work = 2e6;
  std::string idempotency_key;
  int max_active_per_client = 8;
  int max_jobs = 0;
  std::chrono::milliseconds ttl{std::chrono::hours(1)};
  std::chrono::milliseconds timeout{0};  // its render limit from its start; 0: none
  // Rendered by the submitting node alone (rf1_record ends it): no units, no scene stored.
  bool local = false;
  std::vector<std::pair<std::string, std::string>> fields;  // more fields for the job record
};
Result<SubmitResult> submit_job(FarmClient& client, const FarmSubmission& submission);

// The finished job's PNG, when it is still kept.
Result<std::optional<std::string>> job_png(FarmClient& client, std::string_view result_key);

struct NodeConfig {
  ConnectOptions connect;
  FarmConfig farm;
  int workers = 1;
  std::chrono::milliseconds heartbeat{1000};
  std::chrono::milliseconds lease{10000};  // a unit not renewed this long is reclaimed
  // A cancel reaches the node at once on the farm's cancel channel; the states of the jobs
  // being rendered are also read this often, for a message missed while the subscriber
  // reconnected.
  std::chrono::milliseconds cancel_poll{200};
  std::chrono::milliseconds result_ttl{std::chrono::hours(1)};
  // Called with each job canceled anywhere, as the message arrives (a node's own renders of
  // local jobs stop there).
  std::function<void(const std::string&)> on_cancel;
  // This node's renders of local jobs whose progress (0-1000) changed since the last call:
  // written to the farm with each heartbeat, for the other nodes' views of them.
  std::function<std::vector<std::pair<std::string, int>>()> local_progress;
};

struct NodeCounters {
  std::atomic<std::uint64_t> units_rendered{0};
  std::atomic<std::uint64_t> units_stopped{0};     // canceled, or their lease lost
  std::atomic<std::uint64_t> units_failed{0};      // the render could not run
  std::atomic<std::uint64_t> units_reclaimed{0};   // other nodes' units this node requeued
  std::atomic<std::uint64_t> jobs_assembled{0};
  std::atomic<std::uint64_t> jobs_reassembled{0};  // of an assembler that died (as janitor)
  std::atomic<std::uint64_t> jobs_timed_out{0};    // failed by this janitor: past their own limit
  std::atomic<std::uint64_t> jobs_orphaned{0};     // failed by this janitor: local, node gone
  std::atomic<std::uint64_t> redis_calls{0};
  std::atomic<std::uint64_t> redis_micros{0};      // summed round trips
};

class FarmNode {
 public:
  explicit FarmNode(NodeConfig config);
  ~FarmNode();
  FarmNode(const FarmNode&) = delete;
  FarmNode& operator=(const FarmNode&) = delete;

  void start();
  // Graceful: stops taking units, releases the ones it holds (another node takes them at once)
  // and returns when every thread ended.
  void stop();
  // For tests: every thread ends at once and nothing is released or acknowledged, as if the
  // process had been killed (its leases run out and the janitor reclaims its units).
  void abandon();

  const NodeCounters& counters() const { return counters_; }
  const std::string& node() const { return config_.farm.node; }
  // Units being rendered now.
  size_t in_flight() const;

 private:
  struct Held {
    std::string job;
    std::shared_ptr<std::atomic<bool>> stop;
  };
  struct Prepared {
    FarmJob job;
    RenderOptions options;
    std::shared_ptr<const Scene> scene;
    std::shared_ptr<const PreparedRender> render;  // built once for all of the job's units
  };

  // Stops the unit of `entry`: its flag, and its render at once (mid-tile), when it runs.
  void halt(const std::string& entry);
  // Stops every held unit of `job`.
  void halt_job(const std::string& job);
  void work(int index);
  void keep_alive();
  // Subscribed to PREFIX cancel: halts the units of each job canceled anywhere.
  void listen();
  bool render_unit(FarmClient& fc, const Unit& unit, const std::atomic<bool>& stop);
  // Puts the job's image together from its units' results and finishes it.
  void assemble(FarmClient& fc, const FarmJob& farm_job, const std::string& job);
  std::shared_ptr<const Prepared> prepare(FarmClient& fc, const Unit& unit, std::string* error);

  NodeConfig config_;
  std::shared_ptr<FarmSetup> setup_;
  NodeCounters counters_;
  std::atomic<bool> running_{false};
  std::atomic<bool> abandoned_{false};
  std::atomic<bool> listening_{false};  // subscribed to the cancel channel once
  std::vector<std::thread> threads_;

  mutable std::mutex mu_;
  std::map<std::string, Held> held_;  // by stream entry
  std::map<std::string, RenderJob*> rendering_;  // the render of each held entry, while it runs
  // Prepared jobs by id (a few: the jobs being rendered now and recently).
  std::map<std::string, std::shared_ptr<const Prepared>> prepared_;
  std::vector<std::string> prepared_order_;
};

}  // namespace rayfarm::farm
