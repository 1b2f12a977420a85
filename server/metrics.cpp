// Metric collection and exposition.
#include "metrics.h"

#include <sstream>

namespace rayfarm::server {

void Metrics::request(const std::string& route, int status) {
  std::lock_guard lock(mu_);
  ++requests_[{route, status}];
}

void Metrics::render_finished(const std::string& state, double seconds, std::uint64_t primary,
                              std::uint64_t shadow, std::uint64_t reflection) {
  std::lock_guard lock(mu_);
  ++finished_[state];
  size_t b = 0;
  while (b < kBuckets.size() && seconds > kBuckets[b]) ++b;
  ++render_buckets_[b];
  render_sum_ += seconds;
  ++render_count_;
  rays_[0] += primary;
  rays_[1] += shadow;
  rays_[2] += reflection;
}

void Metrics::rejected(const std::string& reason) {
  std::lock_guard lock(mu_);
  ++rejected_[reason];
}

std::string Metrics::render_text(const Gauges& g) const {
  std::lock_guard lock(mu_);
  std::ostringstream o;
  o << "# HELP rayfarm_jobs Jobs in the job table by state.\n# TYPE rayfarm_jobs gauge\n";
  for (const char* s : {"queued", "running", "done", "failed", "canceled"}) {
    auto it = g.jobs_by_state.find(s);
    o << "rayfarm_jobs{state=\"" << s << "\"} " << (it == g.jobs_by_state.end() ? 0 : it->second)
      << "\n";
  }
  o << "# HELP rayfarm_jobs_finished_total Queued jobs that ended, by final state (one answered "
       "from the cache is never queued: rayfarm_cache_hits_total).\n"
       "# TYPE rayfarm_jobs_finished_total counter\n";
  for (const char* s : {"done", "failed", "canceled"}) {
    auto it = finished_.find(s);
    o << "rayfarm_jobs_finished_total{state=\"" << s << "\"} "
      << (it == finished_.end() ? 0 : it->second) << "\n";
  }
  o << "# HELP rayfarm_queue_depth Jobs waiting for a worker.\n# TYPE rayfarm_queue_depth gauge\n"
    << "rayfarm_queue_depth " << g.queue_depth << "\n";
  o << "# HELP rayfarm_jobs_running Jobs being rendered.\n# TYPE rayfarm_jobs_running gauge\n"
    << "rayfarm_jobs_running " << g.running << "\n";
  o << "# HELP rayfarm_workers Render worker threads.\n# TYPE rayfarm_workers gauge\n"
    << "rayfarm_workers " << g.workers << "\n";
  o << "# HELP rayfarm_event_streams Open event streams.\n# TYPE rayfarm_event_streams gauge\n"
    << "rayfarm_event_streams " << g.event_streams << "\n";
  o << "# HELP rayfarm_waiting_requests Requests blocked in wait=1.\n"
       "# TYPE rayfarm_waiting_requests gauge\n"
    << "rayfarm_waiting_requests " << g.waiting_requests << "\n";
  o << "# HELP rayfarm_waiting_scene_loads Large scenes waiting for their turn to be read.\n"
       "# TYPE rayfarm_waiting_scene_loads gauge\n"
    << "rayfarm_waiting_scene_loads " << g.waiting_loads << "\n";
  o << "# HELP rayfarm_render_seconds Render time of finished jobs.\n"
       "# TYPE rayfarm_render_seconds histogram\n";
  std::uint64_t cumulative = 0;
  for (size_t i = 0; i < kBuckets.size(); ++i) {
    cumulative += render_buckets_[i];
    o << "rayfarm_render_seconds_bucket{le=\"" << kBuckets[i] << "\"} " << cumulative << "\n";
  }
  cumulative += render_buckets_[kBuckets.size()];
  o << "rayfarm_render_seconds_bucket{le=\"+Inf\"} " << cumulative << "\n"
    << "rayfarm_render_seconds_sum " << render_sum_ << "\n"
    << "rayfarm_render_seconds_count " << render_count_ << "\n";
  o << "# HELP rayfarm_rays_total Rays traced, by kind.\n# TYPE rayfarm_rays_total counter\n"
    << "rayfarm_rays_total{kind=\"primary\"} " << rays_[0] << "\n"
    << "rayfarm_rays_total{kind=\"shadow\"} " << rays_[1] << "\n"
    << "rayfarm_rays_total{kind=\"reflection\"} " << rays_[2] << "\n";
  o << "# HELP rayfarm_http_requests_total HTTP requests by route and status code.\n"
       "# TYPE rayfarm_http_requests_total counter\n";
  for (auto& [key, n] : requests_)
    o << "rayfarm_http_requests_total{route=\"" << key.first << "\",code=\"" << key.second
      << "\"} " << n << "\n";
  o << "# HELP rayfarm_cache_hits_total Renders answered from the result cache.\n"
       "# TYPE rayfarm_cache_hits_total counter\n"
    << "rayfarm_cache_hits_total " << cache_hits_.load() << "\n"
    << "# HELP rayfarm_cache_misses_total Cacheable renders that had to run.\n"
       "# TYPE rayfarm_cache_misses_total counter\n"
    << "rayfarm_cache_misses_total " << cache_misses_.load() << "\n"
    << "# HELP rayfarm_jobs_merged_total Jobs that took the render of the same image under way "
       "instead of rendering it again.\n# TYPE rayfarm_jobs_merged_total counter\n"
    << "rayfarm_jobs_merged_total " << merged_.load() << "\n"
    << "# HELP rayfarm_cache_bytes Result bytes held in memory.\n# TYPE rayfarm_cache_bytes gauge\n"
    << "rayfarm_cache_bytes " << g.cache_bytes << "\n";
  o << "# HELP rayfarm_rejected_total Requests refused, by reason.\n"
       "# TYPE rayfarm_rejected_total counter\n";
  for (auto& [reason, n] : rejected_)
    o << "rayfarm_rejected_total{reason=\"" << reason << "\"} " << n << "\n";
  return o.str();
}

}  // namespace rayfarm::server
