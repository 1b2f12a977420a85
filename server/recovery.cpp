// Restart recovery: the jobs in the results directory back in the table; unfinished ones are
// queued again with their uploaded textures (failed after a few attempts), done ones whose
// image has expired are dropped, texture files no queued job names are deleted.
#include <algorithm>

#include "rayfarm/load.h"
#include "service.h"

namespace rayfarm::server {

void Service::restore() {
  if (!store_.enabled()) return;
  auto stored = store_.load_jobs();
  std::sort(stored.begin(), stored.end(), [](auto& a, auto& b) {
    return a.record.value("created_ms", 0LL) < b.record.value("created_ms", 0LL);
  });
  constexpr int kMaxAttempts = 3;
  for (auto& s : stored) {
    const nlohmann::json& r = s.record;
    auto job = std::make_shared<Job>();
    job->id = r.value("id", "");
    if (job->id.size() != 32) continue;
    job->client = r.value("client", "");
    job->created_ms = r.value("created_ms", 0LL);
    job->started_ms = r.value("started_ms", 0LL);
    job->finished_ms = r.value("finished_ms", 0LL);
    job->attempts = r.value("attempts", 0);
    job->cache_key = r.value("cache_key", "");
    job->image_name = r.value("image_name", job->id);
    job->error = r.value("error", "");
    job->error_code = r.value("error_code", "");
    job->width = r.value("width", 0);
    job->height = r.value("height", 0);
    // Every option prints as text it reads back; the profile's defaults come back explicit.
    if (r.contains("options") && r["options"].is_object())
      for (auto& [k, v] : r["options"].items())
        if (v.is_string()) apply_option(job->options, k, v.get<std::string>());
    if (r.contains("stats") && r["stats"].is_object()) {
      const auto& st = r["stats"];
      job->stats.primary_rays = st.value("primary", 0ULL);
      job->stats.shadow_rays = st.value("shadow", 0ULL);
      job->stats.reflection_rays = st.value("reflection", 0ULL);
      job->stats.render_ms = st.value("render_ms", 0.0);
      job->stats.spp_done = st.value("spp_done", 0);
      job->stats.error_estimate = st.value("error_estimate", -1.0);
      if (st.contains("parts") && st["parts"].is_array())
        for (auto& p : st["parts"])
          if (p.is_string()) job->stats.parts.push_back(p.get<std::string>());
    }
    auto state = job_state_from(r.value("state", "")).value_or(JobState::failed);
    bool rerun = false;
    if (state == JobState::done) {
      if (!store_.has_image(job->image_name)) {  // its image expired
        store_.remove_job(job->id);
        continue;
      }
      job->stats.finished = true;
      job->stats.spp_target = job->stats.spp_done;
    } else if (!is_final(state)) {
      if (job->attempts >= kMaxAttempts) {
        state = JobState::failed;
        job->error_code = "render_crashed";
        job->error = "the renderer stopped during this job " + std::to_string(job->attempts) +
                     " times; it will not be retried";
        job->finished_ms = now_ms();
      } else {
        std::vector<std::string> textures;
        if (r.contains("textures") && r["textures"].is_array())
          for (auto& t : r["textures"])
            if (t.is_string()) textures.push_back(t.get<std::string>());
        job->scene = reload_scene(s.scene_text, textures);
        if (job->scene) {
          job->textures = std::move(textures);
          state = JobState::queued;
          rerun = true;
        } else {
          state = JobState::failed;
          job->error_code = "lost";
          job->error = "the job's scene could not be read back after a restart";
        }
      }
    }
    job->state = state;
    {
      std::lock_guard lock(mu_);
      job->sequence = ++sequence_;
      jobs_[job->id] = job;
      ++image_refs_[job->image_name];
      for (const std::string& t : job->textures) ++texture_refs_[t];
    }
    if (!rerun && state == JobState::failed) persist(*job);
    if (rerun) scheduler_->submit(job);
  }
  sweep_textures();  // of jobs that ended, or were never accepted, when the process died
}

}  // namespace rayfarm::server
