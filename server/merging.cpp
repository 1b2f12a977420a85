// Jobs of the same image merged while it renders: a class that submits one scene at once, or a
// grader rendering the same references for every student, renders it once. A job whose image
// (its content key) is being rendered by another job waits for that render instead of
// queueing its own: it runs when that one runs, shows its progress, and ends as it ends,
// done with its image or failed with its error. Canceled by its own client, that job lets the
// first job waiting for it render in its place. Outside a farm only: a farm's nodes render
// its jobs' units wherever they are taken.
#include "service.h"

#include <algorithm>

namespace rayfarm::server {
namespace {

// Followers' records are updated from the leader's progress at most this often: every tile
// of a render shared by 200 jobs would otherwise wake every watcher 200 times.
constexpr std::int64_t kMirrorEveryNs = 100'000'000;

}  // namespace

Service::Scheduled Service::schedule(std::shared_ptr<Job> run, const std::string& cache_key) {
  if (farm_ || cache_key.empty()) {
    scheduler_->submit(std::move(run));
    return Scheduled::queued;
  }
  bool follows = false, rendered = false;
  std::string leader;
  int handovers = 0;
  {
    std::lock_guard lock(mu_);
    auto [it, fresh] = in_flight_.try_emplace(cache_key);
    if (fresh) {
      // Rendered meanwhile, between this job's look at the cache and now: its image is there.
      rendered = cache_.get(cache_key) || blobs_.has(BlobKind::image, cache_key);
      if (rendered) {
        in_flight_.erase(it);
      } else {
        it->second.leader = run->id;
        it->second.priority = run->priority;
        run->merge_key = cache_key;
      }
    } else if (it->second.priority <= run->priority) {  // the render is as urgent at least
      it->second.followers.push_back(run);
      follows = true;
      leader = it->second.leader;
      handovers = run->handovers.load();
    }
    // (A job more urgent than the render under way renders its own: it would wait in the
    // other's queue class.)
  }
  if (rendered) {
    JobRecord hit;
    hit.state = JobState::done;
    hit.cache_key = cache_key;
    hit.started_ms = now_ms();
    hit.stats.finished = true;
    hit.stats.spp_target = hit.stats.spp_done = run->options.spp;
    end_followers({std::move(run)}, hit, false);
    return Scheduled::answered;
  }
  if (!follows) {
    scheduler_->submit(std::move(run));
    return Scheduled::queued;
  }
  // Joined a render already running: running too (outside the lock: the record is written
  // to disk). If the render ended meanwhile, its end has decided, and this changes nothing.
  if (auto l = jobs_->get(leader); l && l->state == JobState::running)
    mirror_running(*run, handovers, *l);
  return Scheduled::waits;
}

void Service::mirror_running(Job& follower, int handovers, const JobRecord& leader) {
  // The store applies transitions one at a time, and a handover counts before its own: one
  // decided before it sees the count moved and leaves the record as the handover made it.
  jobs_->transition(follower.id, {JobState::queued}, [&](JobRecord& r) {
    if (follower.handovers.load() != handovers) return;
    r.state = JobState::running;
    r.started_ms = leader.started_ms;  // when its render started
    r.stats = leader.stats;
    ++r.attempts;  // a render that crashes the process counts against each of its jobs
  });
}

std::vector<std::shared_ptr<Job>> Service::take_followers(const Job& leader) {
  if (leader.merge_key.empty()) return {};
  std::lock_guard lock(mu_);
  auto it = in_flight_.find(leader.merge_key);
  if (it == in_flight_.end() || it->second.leader != leader.id) return {};
  std::vector<std::shared_ptr<Job>> followers = std::move(it->second.followers);
  in_flight_.erase(it);
  return followers;
}

std::optional<std::string> Service::leader_of(const std::string& id,
                                              const std::string& cache_key) const {
  if (cache_key.empty()) return std::nullopt;
  std::lock_guard lock(mu_);
  auto it = in_flight_.find(cache_key);
  if (it == in_flight_.end()) return std::nullopt;
  for (const auto& f : it->second.followers)
    if (f->id == id) return it->second.leader;
  return std::nullopt;
}

std::size_t Service::followers_of(const std::string* client) const {
  std::size_t n = 0;
  std::lock_guard lock(mu_);
  for (const auto& [key, f] : in_flight_)
    for (const auto& job : f.followers) n += !client || job->client == *client;
  return n;
}

void Service::on_progress(Job& job, const RenderStats& stats) {
  jobs_->update_progress(job.id, stats);
  if (farm_) farm_->local_progress(job.id, stats.progress());  // every job here is local
  if (job.merge_key.empty()) return;
  const std::int64_t now = std::chrono::steady_clock::now().time_since_epoch().count();
  std::int64_t last = job.mirrored_ns.load();
  if (now - last < kMirrorEveryNs || !job.mirrored_ns.compare_exchange_strong(last, now)) return;
  std::vector<std::string> ids;
  {
    std::lock_guard lock(mu_);
    auto it = in_flight_.find(job.merge_key);
    if (it == in_flight_.end() || it->second.leader != job.id) return;
    for (const auto& f : it->second.followers) ids.push_back(f->id);
  }
  for (const std::string& id : ids) jobs_->update_progress(id, stats);
}

void Service::end_followers(std::vector<std::shared_ptr<Job>> followers, const JobRecord& leader,
                            bool requeue) {
  for (auto& f : followers) {
    const auto before = jobs_->get(f->id);
    if (!before) continue;
    if (before->cancel_requested) {  // canceled by its client while it was handed over
      f->cancel_requested = true;
      on_finished(*f, nullptr);
      continue;
    }
    if (requeue) {
      // To render itself, from the start (the first one; the rest wait for it).
      f->handovers.fetch_add(1);
      jobs_->transition(f->id, {JobState::queued, JobState::running}, [](JobRecord& r) {
        if (r.state == JobState::running) r.attempts = std::max(0, r.attempts - 1);
        r.state = JobState::queued;
        r.started_ms = 0;
        r.stats = RenderStats{};
      });
      schedule(std::move(f), leader.cache_key);
      continue;
    }
    f->handovers.fetch_add(1);
    auto after = jobs_->transition(f->id, {JobState::queued, JobState::running}, [&](JobRecord& r) {
      r.state = leader.state;
      r.error_code = leader.error_code;
      r.error = leader.error;
      if (r.started_ms == 0) r.started_ms = leader.started_ms;
      r.finished_ms = now_ms();
      r.stats = leader.stats;
      r.cache_hit = leader.state == JobState::done;  // its image is another job's render
      r.textures.clear();
    });
    f->scene.reset();
    if (after) release_textures(before->textures);
  }
}

}  // namespace rayfarm::server
