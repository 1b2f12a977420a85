// Restart recovery: the jobs the store kept are taken up again. Unfinished ones are queued
// again with their uploaded textures (failed after a few attempts, canceled when their client
// asked; on a farm node, failed in the farm), done ones whose image has expired are dropped,
// and texture files no queued job names are deleted.
#include <algorithm>

#include "rayfarm/load.h"
#include "service.h"

namespace rayfarm::server {

void Service::restore() {
  if (!blobs_.durable()) return;
  constexpr int kMaxAttempts = 3;
  for (const JobRecord& r : jobs_->all()) {
    if (r.state == JobState::done && !blobs_.has(BlobKind::image, r.image_name)) {
      jobs_->remove(r.id);  // its image expired
      continue;
    }
    if (farm_ && !is_final(r.state)) {
      // A farm node's unfinished job is the farm's to answer for, on every node alike: it
      // failed with the process, and the farm's record, not this node's, is the one every
      // node reads. If Redis cannot be told now (one try: a start is not held up), this node
      // says failed too, and the farm's job limit ends the farm's record.
      const std::string why = "the node rendering it restarted; submit it again";
      if (farm_->finish_local(r, JobState::failed, "node_lost", why, nullptr, RenderStats{}, 1)) {
        jobs_->remove(r.id);
      } else {
        jobs_->transition(r.id, {JobState::queued, JobState::running}, [&](JobRecord& x) {
          x.state = JobState::failed;
          x.error_code = "node_lost";
          x.error = why;
          x.finished_ms = now_ms();
          x.textures.clear();
        });
      }
      continue;
    }
    {
      std::lock_guard lock(mu_);
      ++image_refs_[r.image_name];
    }
    if (is_final(r.state)) continue;
    auto fail = [&](JobState state, std::string code, std::string message) {
      jobs_->transition(r.id, {JobState::queued, JobState::running}, [&](JobRecord& x) {
        x.state = state;
        x.error_code = code;
        x.error = message;
        x.finished_ms = now_ms();
        x.textures.clear();
      });
    };
    if (r.cancel_requested) {
      fail(JobState::canceled, "", "");
      continue;
    }
    if (r.attempts >= kMaxAttempts) {
      fail(JobState::failed, "render_crashed",
           "the renderer stopped during this job " + std::to_string(r.attempts) +
               " times; it will not be retried");
      continue;
    }
    auto text = blobs_.get(BlobKind::scene, r.id);
    auto scene = text ? reload_scene(*text, r.textures) : nullptr;
    if (!scene) {
      fail(JobState::failed, "lost", "the job's scene could not be read back after a restart");
      continue;
    }
    // Queued again, to run from the start: no progress or start of the render it lost.
    jobs_->transition(r.id, {JobState::queued, JobState::running}, [](JobRecord& x) {
      x.state = JobState::queued;
      x.started_ms = 0;
      x.stats = RenderStats{};
    });
    {
      std::lock_guard lock(mu_);
      for (const std::string& t : r.textures) ++texture_refs_[t];
    }
    auto run = std::make_shared<Job>();
    run->id = r.id;
    run->client = r.client;
    run->priority = r.options.priority;
    run->scene = std::move(scene);
    run->options = r.options;
    schedule(std::move(run), r.cache_key);
  }
  sweep_textures();  // of jobs that ended, or were never accepted, when the process died
}

}  // namespace rayfarm::server
