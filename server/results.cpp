// A render's course in the job's record (running, then its final state) and its image stored
// when it ends, and the image read back (cache, then blobs) for the result routes.
#include "rayfarm/image_io.h"
#include "service.h"

namespace rayfarm::server {
namespace {

// The cache's key of a stopped job's partial image: no image name has a '#'.
std::string partial_key(const std::string& image_name) { return image_name + "#partial"; }

}  // namespace

bool Service::on_started(Job& job, const RenderStats& stats) {
  auto rec = jobs_->transition(job.id, {JobState::queued}, [&](JobRecord& r) {
    r.state = JobState::running;
    r.started_ms = now_ms();
    r.stats = stats;
    ++r.attempts;
  });
  if (rec && rec->cancel_requested) job.cancel_requested = true;
  if (rec && !rec->cancel_requested && !job.merge_key.empty()) {
    // The jobs waiting for this render run with it.
    std::vector<std::pair<std::shared_ptr<Job>, int>> followers;
    {
      std::lock_guard lock(mu_);
      if (auto it = in_flight_.find(job.merge_key);
          it != in_flight_.end() && it->second.leader == job.id)
        for (const auto& f : it->second.followers) followers.emplace_back(f, f->handovers.load());
    }
    for (const auto& [f, handovers] : followers) mirror_running(*f, handovers, *rec);
  }
  return rec && !rec->cancel_requested;
}

void Service::on_finished(Job& job, RenderJob* render) {
  RenderStats st = render ? render->stats() : RenderStats{};
  JobState state;
  std::string code, message;
  {
    std::lock_guard jl(job.mu);
    code = job.error_code;
    message = job.error;
  }
  const auto before = jobs_->get(job.id);
  const bool canceled = job.cancel_requested || (before && before->cancel_requested);
  if (!render) {
    state = message.empty() ? JobState::canceled : JobState::failed;
  } else if (job.timed_out) {
    state = JobState::failed;
    code = "timeout";
    st.stop_reason = "job_timeout";  // the render saw only a cancel
    message = "the job ran longer than the server's limit of " +
              format_number(settings_.job_timeout) +
              " s: lower spp, max_depth or the image size, or give time_limit to stop "
              "sampling in time";
  } else if (!message.empty()) {
    state = JobState::failed;
  } else if (st.stop_reason == "canceled") {
    // Stopped by its client, or interrupted by a shutdown (a cancel that came after the
    // last tile does not discard a complete image).
    state = canceled || !scheduler_->interrupted() ? JobState::canceled : JobState::queued;
  } else {
    state = JobState::done;
  }
  if (state == JobState::queued) {
    // Interrupted by a shutdown: it stays queued on disk and runs again after a restart, from
    // the start, so it shows no progress, start or stop of the render that was cut short.
    jobs_->transition(job.id, {JobState::running}, [&](JobRecord& r) {
      r.state = JobState::queued;
      r.attempts = std::max(0, r.attempts - 1);
      r.started_ms = 0;
      r.stats = RenderStats{};
    });
    // So are the jobs that waited for it (they wait again after the restart).
    for (const auto& f : take_followers(job))
      jobs_->transition(f->id, {JobState::running}, [](JobRecord& r) {
        r.state = JobState::queued;
        r.attempts = std::max(0, r.attempts - 1);
        r.started_ms = 0;
        r.stats = RenderStats{};
      });
    return;
  }
  std::shared_ptr<const std::string> png;
  // What a job stopped part way had rendered stays for ?partial=1, in memory only (the
  // image cache's budget bounds it; a restart forgets it).
  if (render && (state == JobState::canceled || state == JobState::failed) &&
      st.progress() > 0) {
    try {
      auto bytes = encode_png(render->image());
      cache_.put(partial_key(before ? before->image_name : job.id),
                 std::make_shared<const std::string>(bytes.begin(), bytes.end()));
    } catch (const std::exception&) {
      // Out of memory: its partial image is black, as before it stopped.
    }
  }
  if (state == JobState::done) {
    try {
      auto bytes = encode_png(render->image());
      png = std::make_shared<const std::string>(bytes.begin(), bytes.end());
      std::string name = before ? before->image_name : job.id;
      blobs_.put(BlobKind::image, name, *png);
      cache_.put(name, png);
    } catch (const std::exception& ex) {
      state = JobState::failed;
      code = "storage_error";
      message = std::string("could not store the result: ") + ex.what();
    }
  }
  // A farm's job rendered here: the farm's record ends first, so whichever node a client
  // asks next, once this node says done, finds the image.
  if (farm_ && before)
    farm_->finish_local(*before, state, code, message, state == JobState::done ? png.get() : nullptr,
                        st);
  auto after = jobs_->transition(job.id, {JobState::queued, JobState::running}, [&](JobRecord& r) {
    r.state = state;
    r.error_code = code;
    r.error = message;
    r.finished_ms = now_ms();
    if (render) r.stats = st;
    if (!render && !message.empty()) ++r.attempts;  // the scene could not be prepared
    r.textures.clear();
  });
  // The jobs that waited for this render end as it did; canceled, it leaves the render to
  // the first of them.
  if (auto followers = take_followers(job); !followers.empty()) {
    JobRecord ended = after ? *after : before.value_or(JobRecord{});
    ended.state = state;
    ended.error_code = code;
    ended.error = message;
    ended.cache_key = job.merge_key;
    if (render) ended.stats = st;
    end_followers(std::move(followers), ended, state == JobState::canceled);
  }
  // Only a render needs the scene, and a final job never runs again.
  job.scene.reset();
  // After the final record is stored: a crash in between leaves files the next start sweeps,
  // never a queued record whose textures are gone.
  if (before && after) release_textures(before->textures);
  metrics_.render_finished(std::string(to_string(state)), st.render_ms / 1000, st.primary_rays,
                           st.shadow_rays, st.reflection_rays);
}

std::shared_ptr<const std::string> Service::result_png(const JobRecord& job) {
  if (auto hit = cache_.get(job.image_name)) return hit;
  if (farm_) return farm_->png(job.image_name);
  if (auto stored = blobs_.get(BlobKind::image, job.image_name)) {
    auto png = std::make_shared<const std::string>(std::move(*stored));
    cache_.put(job.image_name, png);
    return png;
  }
  return nullptr;
}

std::optional<Image> Service::current_image(const JobRecord& job) {
  if (auto render = scheduler_->render_of(job.id)) return render->image();
  if (!is_final(job.state))
    if (auto leader = leader_of(job.id, job.cache_key))
      if (auto render = scheduler_->render_of(*leader)) return render->image();
  if (job.state == JobState::done) {
    auto png = result_png(job);
    if (!png) return std::nullopt;
    std::string error;
    return decode_image(*png, &error);
  }
  if (job.state == JobState::canceled || job.state == JobState::failed)
    if (auto png = cache_.get(partial_key(job.image_name))) {
      std::string error;
      if (auto image = decode_image(*png, &error)) return image;
    }
  return Image(job.width, job.height);  // not started, or ended without an image: black
}

}  // namespace rayfarm::server
