// A render's outcome: its final state and image stored when it ends, and the image read back
// (cache, then disk) for the result routes.
#include "rayfarm/image_io.h"
#include "service.h"

namespace rayfarm::server {

void Service::on_finished(Job& job, RenderJob* render) {
  RenderStats st = render ? render->stats() : RenderStats{};
  JobState state;
  std::string code, message;
  std::shared_ptr<const std::string> png;
  {
    std::lock_guard jl(job.mu);
    if (!render) {
      state = job.error.empty() ? JobState::canceled : JobState::failed;
      code = job.error_code;
      message = job.error;
    } else if (job.timed_out) {
      state = JobState::failed;
      code = "timeout";
      message = "the job ran longer than the server's limit of " +
                format_number(settings_.job_timeout) +
                " s: lower spp, max_depth or the image size, or give time_limit to stop "
                "sampling in time";
    } else if (!job.error.empty()) {
      state = JobState::failed;
      code = job.error_code;
      message = job.error;
    } else if (st.stop_reason == "canceled") {
      // Stopped by its client, or interrupted by a shutdown (a cancel that came after the
      // last tile does not discard a complete image).
      state = job.cancel_requested ? JobState::canceled : JobState::queued;
    } else {
      state = JobState::done;
    }
  }
  if (state == JobState::queued) {
    // Interrupted by a shutdown: it stays queued on disk and runs again after a restart.
    std::lock_guard jl(job.mu);
    job.state = JobState::queued;
    job.attempts = std::max(0, job.attempts - 1);
    job.stats = st;
  } else {
    if (state == JobState::done) {
      try {
        auto bytes = encode_png(render->image());
        png = std::make_shared<const std::string>(bytes.begin(), bytes.end());
        store_.save_image(job.image_name, *png);
        cache_.put(job.image_name, png);
      } catch (const std::exception& ex) {
        state = JobState::failed;
        code = "storage_error";
        message = std::string("could not store the result: ") + ex.what();
      }
    }
    std::lock_guard jl(job.mu);
    job.state = state;
    job.error_code = code;
    job.error = message;
    job.finished_ms = now_ms();
    job.stats = render ? st : job.stats;
    job.render.reset();
    // Only a render needs the scene, and a final job never runs again: a busy day keeps
    // thousands of finished jobs, so they keep only their record.
    job.scene.reset();
    ++job.version;
  }
  job.changed.notify_all();
  persist(job);
  // After the final record is on disk: a crash in between leaves files the next start sweeps,
  // never a queued record whose textures are gone.
  if (state != JobState::queued) release_textures(job);
  if (state != JobState::queued)
    metrics_.render_finished(std::string(to_string(state)), st.render_ms / 1000, st.primary_rays,
                             st.shadow_rays, st.reflection_rays);
}

std::shared_ptr<const std::string> Service::result_png(const Job& job) {
  if (auto hit = cache_.get(job.image_name)) return hit;
  if (auto disk = store_.load_image(job.image_name)) {
    auto png = std::make_shared<const std::string>(std::move(*disk));
    cache_.put(job.image_name, png);
    return png;
  }
  return nullptr;
}

std::optional<Image> Service::current_image(const Job& job) {
  std::shared_ptr<RenderJob> render;
  JobState state;
  {
    std::lock_guard jl(job.mu);
    render = job.render;
    state = job.state;
  }
  if (render) return render->image();
  if (state == JobState::done) {
    auto png = result_png(job);
    if (!png) return std::nullopt;
    std::string error;
    return decode_image(*png, &error);
  }
  return Image(job.width, job.height);  // not started: black
}

}  // namespace rayfarm::server
