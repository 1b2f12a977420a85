// A job as this process renders it: the scene and options a worker needs, and the render in
// progress. What outlives the process is its JobRecord (job_record.h), kept by the JobStore;
// nothing here is seen by the HTTP routes.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include "job_record.h"
#include "rayfarm/options.h"
#include "rayfarm/render.h"
#include "rayfarm/scene.h"

namespace rayfarm::server {

struct Job {
  std::string id;
  std::string client;
  Priority priority = Priority::normal;
  std::shared_ptr<const Scene> scene;
  RenderOptions options;
  // Its image's content key while other jobs wait for this render of the same image
  // (Service::in_flight_); empty otherwise.
  std::string merge_key;
  std::atomic<std::int64_t> mirrored_ns{0};  // when its progress was last given to them
  // Times it was handed on by a render it waited for: a "running with it" that was decided
  // before the last handover is stale and changes nothing.
  std::atomic<int> handovers{0};

  // Set by the scheduler; `mu` guards render, error and error_code.
  mutable std::mutex mu;
  std::shared_ptr<RenderJob> render;
  std::string error;       // the render threw, or the scene could not be prepared
  std::string error_code;
  // What its tiles took of the render threads, summed (--job-timeout weighs it over their
  // number): a job sharing them with others is not timed out for their load.
  std::atomic<std::int64_t> render_ns{0};
  std::atomic<bool> cancel_requested{false};  // by its client (not by a shutdown)
  std::atomic<bool> timed_out{false};
};

}  // namespace rayfarm::server
